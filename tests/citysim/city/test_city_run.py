"""A three-street city on a real Dask LocalCluster over TCP on loopback; a killed run resumes to the
same city.json; one street's payback and NPV worked out by hand from its year's energies."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from citysim.city.run import CityOptions, run_city
from citysim.city.spec import load_city
from tests.citysim.city.conftest import COSTS, STREETS, write_city

REPO = Path(__file__).resolve().parents[3]
OPTIONS = {"min_lit_on_entry": 0.0, "progress": False}


@pytest.fixture(scope="module")
def city_run(tmp_path_factory):
    """The toy city run once, uninterrupted, on a LocalCluster of two worker processes on 127.0.0.1."""
    from distributed import LocalCluster

    folder = tmp_path_factory.mktemp("city")
    city_file = write_city(folder / "in")
    out = folder / "out"
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", protocol="tcp://",
                      dashboard_address="127.0.0.1:0") as cluster:  # fmt: skip
        address = cluster.scheduler_address
        result = run_city(load_city(city_file), city_file, out, CityOptions(scheduler=address, **OPTIONS))
    return {"address": address, "result": result, "out": out, "city_file": city_file}


@pytest.mark.slow
def test_a_three_street_city_runs_on_a_local_cluster_over_tcp(city_run):
    assert city_run["address"].startswith("tcp://127.0.0.1:")
    result, out = city_run["result"], city_run["out"]
    assert result["counts"] == {"streets": 3, "skipped": 0, "ran": 3}
    assert [s["name"] for s in result["streets"]] == [s[0] for s in STREETS]
    assert [s["lamps"] for s in result["streets"]] == [s[2] for s in STREETS]
    pids = {json.loads((out / "streets" / s[0] / "task.json").read_text())["pid"] for s in STREETS}
    assert os.getpid() not in pids  # the years ran in the cluster's worker processes, not here
    for street in result["streets"]:
        year = json.loads((out / "streets" / street["name"] / "year.json").read_text())
        assert year["site"]["timezone"] == "Europe/Berlin"  # the city's site, not the street's own
        assert year["money"]["price_per_kwh"] == 0.3  # the city's costs, not the street's 9.0
        assert street["controllers"]["pir"]["energy_kwh_per_year"] < street["controllers"]["always_on"]["energy_kwh_per_year"]
    # busier and longer streets use more energy with lamps always on
    kwh = [s["controllers"]["always_on"]["energy_kwh_per_year"] for s in result["streets"]]
    assert kwh == sorted(kwh)
    assert (out / "city.csv").read_text().count("\n") == 4
    assert [r["rank"] for r in result["ranking"]] == [1, 2, 3]
    paybacks = [r["payback_years"] for r in result["ranking"]]
    assert paybacks == sorted(paybacks)


@pytest.mark.slow
def test_payback_and_npv_of_one_street_by_hand(city_run):
    street = next(s for s in city_run["result"]["streets"] if s["name"] == "oak")
    ao, pir = street["controllers"]["always_on"], street["controllers"]["pir"]
    saved_kwh = ao["energy_kwh_per_year"] - pir["energy_kwh_per_year"]
    poles = 3
    capex = poles * (50.0 + 100.0 + 50.0)  # PIR + controller node + installation, per pole
    opex = poles * (2.0 + 3.0)
    net = saved_kwh * 0.3 - opex  # the price does not change (COSTS), so every year saves the same
    annuity = (1 - 1.05**-10) / 0.05  # present value of 1 a year for 10 years at 5 %
    assert COSTS["energy_price_change_per_year"] == 0.0
    assert pir["capex"] == pytest.approx(capex)
    assert pir["opex_per_year"] == pytest.approx(opex)
    assert pir["money_saved_per_year"] == pytest.approx(net)
    assert pir["payback_years"] == pytest.approx(capex / net)
    assert pir["npv"] == pytest.approx(-capex + net * annuity)
    assert pir["co2_avoided_kg_over_lifetime"] == pytest.approx(saved_kwh * 0.4 * 10)  # the street's year factor


def _city(city_file: Path, out: Path, **popen) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    argv = [sys.executable, "-m", "citysim", "city", str(city_file), "--out", str(out), "--workers", "1",
            "--min-lit-on-entry", "0", "--no-progress"]  # fmt: skip
    return subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, **popen)


@pytest.mark.slow
def test_a_city_killed_half_way_resumes_to_the_same_city_json(city_run):
    out = city_run["out"].parent / "killed"
    proc = _city(city_run["city_file"], out, start_new_session=True)  # its own group: cluster and all
    done: list[Path] = []
    deadline = time.monotonic() + 240
    while not done and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.1)
        done = list(out.glob("streets/*/year.json"))
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert 1 <= len(done) < 3, "killed after one street and before the last"
    assert not (out / "city.json").exists()
    resumed = _city(city_run["city_file"], out)
    text, _ = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, text
    assert f"{len(done)} already done" in text
    assert (out / "city.json").read_bytes() == (city_run["out"] / "city.json").read_bytes()
    assert (out / "city.csv").read_bytes() == (city_run["out"] / "city.csv").read_bytes()
    assert (out / "report.html").exists() and (out / "plots" / "city_map.png").exists()
