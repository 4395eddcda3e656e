import cProfile, pstats, time, sys, tempfile
from pathlib import Path
from citysim.config.scenario import load_scenario
from citysim.sim.loop import run_controller, controller_spec
from citysim.sim.replay import record_traffic
from citysim.sim.calibration import sensor_model_for
from experiments.bench.night import night_hour, SUBURBAN

hour, dur = int(sys.argv[1]), float(sys.argv[2])
names = sys.argv[3].split(",")
base = load_scenario(SUBURBAN)
scen = night_hour(base, hour, dur)
model = sensor_model_for(scen, Path("scenarios/sensor_models"))
tmp = Path(tempfile.mkdtemp())
t0 = time.process_time()
record_traffic(scen, tmp / "traffic")
print("record", round(time.process_time() - t0, 2))
for name in names:
    spec = controller_spec(scen, name)
    t0 = time.process_time()
    if len(sys.argv) > 4:
        pr = cProfile.Profile(); pr.enable()
    s = run_controller(scen, spec, traffic=tmp / "traffic", fidelity="fast", sensor_model=model)
    if len(sys.argv) > 4:
        pr.disable(); pstats.Stats(pr).sort_stats(sys.argv[4]).print_stats(45)
    print(name, round(time.process_time() - t0, 2), "cpu s", s["savings_vs_always_on"], s["lit_on_entry_rate"])
