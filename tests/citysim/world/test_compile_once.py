"""On a fresh clone (an empty numba cache) each world kernel compiles for one signature only: a
second one (a literal flag, an int where a float goes, another array layout) is a second full
compile, paid before the first simulated chunk exists. The kernels numba inlines into their
callers (``citysim.world.jit``) are not compiled on their own by the step."""

import json
import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
#: Two minutes of five times the suburban traffic at 30 Hz (agents come and go), then each kernel's
#: signatures and whether numba inlines it.
RUN = """
import json
import numpy as np
import simpy
from numba.core.registry import CPUDispatcher
from citysim.config.scenario import load_scenario, override
from citysim.world import behaviour_compiled, conflicts_compiled, moves_compiled, physics
from citysim.world.street import build_street
from citysim.world.traffic import start_traffic

scenario = load_scenario("scenarios/suburban_night.yaml")
classes = ("pedestrian", "group", "cyclist", "vehicle", "animal")
busy = override(scenario, {f"traffic.classes.{k}.rate_per_hour": getattr(scenario.traffic.classes, k).rate_per_hour * 5
                           for k in classes})
rng = np.random.default_rng(busy.seed)
world = physics.World(build_street(busy), rng.spawn(1)[0])
env = simpy.Environment()
start_traffic(env, world, busy, rng)
for k in range(30 * 120):
    env.run(until=(k + 1) / 30)
    world.step(1 / 30)
print(json.dumps({"removed": world.removed_count, "kernels": {
    name: [[str(s) for s in d.signatures], d.targetoptions.get("inline") == "always"]
    for m in (behaviour_compiled, conflicts_compiled, moves_compiled)
    for name, d in vars(m).items() if isinstance(d, CPUDispatcher) and d.__module__ == m.__name__}}))
"""


def test_a_cold_run_compiles_each_world_kernel_for_one_signature(tmp_path):
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(REPO)}
    done = subprocess.run([sys.executable, "-c", RUN], cwd=REPO, env=env, capture_output=True, text=True, check=True)
    out = json.loads(done.stdout.splitlines()[-1])
    assert out["removed"] > 0
    kernels = out["kernels"]
    assert len(kernels) > 20
    for name, (signatures, inline) in kernels.items():
        # the inlined compile within their callers only; Python calls commit after numpy's overlap check
        if inline:
            assert len(signatures) <= (name == "commit"), (name, signatures)
        else:
            assert len(signatures) == 1, (name, signatures)
