"""Sweeps: case specs, the pure run_case, grids and Monte-Carlo draws, the engine (in-process and on a Dask
LocalCluster), resumable results, Table 4.1 through the engine, tables, gain tuning and the CLI."""

from __future__ import annotations

import doctest
import json
import math
import os
import pickle
import signal
import sys
import threading
import time
from dataclasses import replace
from pathlib import Path

import pytest

from switchobs import _progress
from switchobs.cli.main import main
from switchobs.exceptions import PrerequisiteError, SimulationError
from switchobs.plants import table41
from switchobs.sweep import (BrakingCase, CaseResult, CertifyCase, Choice, Integers, RoadChanges, Uniform, _analysis, _engine, _run,
                             _case, _grid, case_from_json, certify_grid, grid, load_sweep_spec, monte_carlo,
                             monte_carlo_case, pareto_front, read_results, run_case, run_sweep, summary_table,
                             tune_betas)

ROOT = Path(__file__).resolve().parents[1]
#: Short brakings (about 0.5 s simulated each) for the engine tests.
QUICK = grid(BrakingCase(speed_kmh=30.0), road=["dry-asphalt", "wet-asphalt"], controller=["five-phase", "two-phase"])


@pytest.mark.parametrize("module", [_case, _grid, _analysis, _run, _engine, _progress])
def test_doctests_of_the_sweep_modules(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_case_specs_are_hashable_picklable_and_keyed_by_their_content():
    case = BrakingCase(road="snow", speed_kmh=90, changes=[["ice", 1]], observer="xbs4", beta1=80, beta2=120)
    same = BrakingCase(road="snow", speed_kmh=90.0, changes=(("ice", 1.0),), observer="xbs4", beta1=80.0,
                       beta2=120.0)
    assert case == same and hash(case) == hash(same) and case.case_id == same.case_id
    assert pickle.loads(pickle.dumps(case)) == case
    assert case_from_json(json.loads(json.dumps(case.to_json()))) == case
    assert BrakingCase(road="snow", speed_kmh=91.0).case_id != BrakingCase(road="snow", speed_kmh=90.0).case_id
    cert = CertifyCase(betas=[("beta1", 100), ("beta2", 150)], box=[("a", 150, 250)], discrete="rk4")
    assert case_from_json(cert.to_json()) == cert and cert.case_id != case.case_id


@pytest.mark.parametrize("kwargs, match", [
    ({"road": "mud"}, r"unknown road 'mud'"),
    ({"speed_kmh": -5.0}, r"speed_kmh must be > 0, got -5"),
    ({"changes": (("snow", 2.0), ("ice", 1.0))}, r"road change times must increase"),
    ({"observer": "adaptive", "beta2": 3.0}, r"adaptive observer has one rate"),
    ({"encoder_ppr": 1}, r"encoder_ppr must be 0 \(exact signals\) or >= 2"),
    ({"controller": "six-phase"}, r"unknown controller 'six-phase'"),
])
def test_bad_braking_cases_are_refused_with_the_offending_value(kwargs, match):
    with pytest.raises(SimulationError, match=match):
        BrakingCase(**kwargs)


def test_grid_and_monte_carlo_cases_rebuild_alone_with_their_seeds():
    cases = grid(BrakingCase(), road=["snow", "ice"], speed_kmh=[60.0, 90.0, 120.0])
    assert [(c.road, c.speed_kmh) for c in cases[:4]] == [("snow", 60.0), ("snow", 90.0), ("snow", 120.0),
                                                          ("ice", 60.0)]
    draws = {"road": Choice(("snow", "ice", "dry-asphalt")), "speed_kmh": Uniform(30.0, 200.0),
             "encoder_seed": Integers(0, 10**6),
             "changes": RoadChanges(("wet-asphalt", "snow"), 0, 2, (0.5, 2.0))}
    study = monte_carlo(BrakingCase(observer="xbs4", encoder_ppr=60), 50, draws=draws, root_seed=11)
    assert len({c.case_id for c in study}) == 50
    assert study[37] == monte_carlo_case(BrakingCase(observer="xbs4", encoder_ppr=60), 37, draws=draws,
                                         root_seed=11)
    assert study != monte_carlo(BrakingCase(observer="xbs4", encoder_ppr=60), 50, draws=draws, root_seed=12)
    assert {len(c.changes) for c in study} == {0, 1, 2} and all(30 <= c.speed_kmh < 200 for c in study)
    with pytest.raises(SimulationError, match=r"no field\(s\) \['speed'\]"):
        grid(BrakingCase(), speed=[1.0])


def test_a_case_that_raises_is_a_row_with_its_error():
    res = run_case(BrakingCase(speed_kmh=2.0))  # below the 2.5 km/h stop speed
    assert res.status == "error" and not res.ok
    assert res.error.startswith("SimulationError: ") and "stop speed" in res.error
    assert CaseResult.from_json(json.loads(json.dumps(res.to_json()))).to_json() == res.to_json()


def test_braking_case_metrics_with_an_observer_and_a_road_change():
    res = run_case(BrakingCase(road="dry-asphalt", speed_kmh=60.0, changes=(("wet-asphalt", 0.6),),
                               observer="xbs4", beta1=100.0, beta2=150.0), series=True)
    m = res.metrics
    assert res.status == "stopped" and m["stopping_distance_m"] > 0 and m["abs_cycles"] > 0
    assert [s["segment"] for s in m["segments"]] == ["dry-asphalt", "wet-asphalt", "whole run"]
    assert [r["label"] for r in m["reconvergence"]] == ["initial", "-> wet-asphalt"]
    assert m["xbs_rms"] > 0 and m["xbs_rms_settled"] <= m["segments"][-1]["rms"]
    assert len(res.series["t"]) == m["steps"] + 1 and "series" in res.to_json()


def test_certification_case_reports_verdict_dwell_time_and_discrete_bound():
    cases = certify_grid(CertifyCase(model="abs-xbs4", discrete="radau3"), beta1=[100.0], beta2=[150.0])
    res = run_case(cases[0])
    assert res.status == "certified" and res.metrics["certified"] is True
    assert res.metrics["spectrum"] == ["-100", "-100", "-150", "-150"]
    assert res.metrics["dwell_time"] == "any" and res.metrics["discrete_certified"] is True
    assert res.metrics["h_max"] == "inf"  # radau3 is certified for every step length


def test_serial_sweep_streams_rows_and_refuses_to_overwrite(tmp_path):
    path = tmp_path / "rows.jsonl"
    sweep = run_sweep([*QUICK, QUICK[0]], path=path, scheduler="none")
    assert len(sweep.results) == 4 and sweep.resumed == 0 and not sweep.failed
    rows = [json.loads(line) for line in path.read_text().splitlines()]
    assert [r["case_id"] for r in rows] == [c.case_id for c in QUICK]
    assert [r.to_json() for r in read_results(path)] == rows
    with pytest.raises(SimulationError, match="exists; resume it"):
        run_sweep(QUICK, path=path, scheduler="none")


def test_a_resumed_sweep_gives_the_same_file_as_an_uninterrupted_one(tmp_path):
    # with encoder-fed cases, as in the robustness study: one finished before the kill, one after
    encoder = grid(BrakingCase(road="wet-asphalt", speed_kmh=40.0, changes=(("snow", 0.4),), observer="xbs4",
                               method="radau3", encoder_ppr=60, stop_kmh=10.0, duration_s=0.8), encoder_seed=[1, 2])
    cases = [*QUICK, *encoder]
    whole = tmp_path / "whole.jsonl"
    run_sweep(cases, path=whole, scheduler="none")
    killed = tmp_path / "killed.jsonl"
    run_sweep([QUICK[2], QUICK[0], encoder[0]], path=killed, scheduler="none")
    with open(killed, "a", encoding="utf-8") as fh:  # a kill in the middle of a write
        fh.write(json.dumps(json.loads(whole.read_text().splitlines()[1]))[:40])
    resumed = run_sweep(cases, path=killed, resume=True, scheduler="none")
    assert resumed.resumed == 3 and resumed.results[-1].metrics["recovery_s"]
    assert killed.read_bytes() == whole.read_bytes()


def test_a_parquet_results_file_holds_the_json_lines_rows_and_resumes_after_a_kill(tmp_path):
    pa = pytest.importorskip("pyarrow", reason="pyarrow is not installed: Parquet results NOT checked")
    import pyarrow.parquet as pq

    cases = [*QUICK, CertifyCase(model="abs-xbs3")]
    lines = tmp_path / "rows.jsonl"
    run_sweep(cases, path=lines, scheduler="none")
    rows = [json.loads(line) for line in lines.read_text().splitlines()]
    table_path = tmp_path / "rows.parquet"
    sweep = run_sweep(cases, path=table_path, scheduler="none")
    assert sweep.path == table_path and not _engine._journal(table_path).exists()
    assert [r.to_json() for r in read_results(table_path)] == rows
    table = pq.read_table(table_path)
    # typed columns for analysis: the case's and the metrics' scalar fields, None where a kind has none
    assert table.column("case_id").to_pylist() == [r["case_id"] for r in rows]
    assert table.schema.field("case.speed_kmh").type == pa.float64()
    assert table.column("metrics.stopping_distance_m").to_pylist() == [
        r["metrics"].get("stopping_distance_m") for r in rows]
    assert table.column("case.changes").to_pylist()[0] == json.dumps(rows[0]["case"]["changes"])
    with pytest.raises(SimulationError, match="exists; resume it"):
        run_sweep(cases, path=table_path, scheduler="none")
    # killed after two cases, the second row torn: the journal holds what a resume needs, no table yet
    killed = tmp_path / "killed.parquet"
    journal = _engine._journal(killed)
    journal.write_text(lines.read_text().splitlines(keepends=True)[0] + lines.read_text().splitlines()[1][:50])
    with pytest.raises(SimulationError, match="killed.parquet.rows.jsonl' exists; resume it"):
        run_sweep(cases, path=killed, scheduler="none")
    resumed = run_sweep(cases, path=killed, resume=True, scheduler="none")
    assert resumed.resumed == 1 and not journal.exists()
    assert pq.read_table(killed).equals(table)
    # a table already written and a resume: nothing runs, the same table
    again = run_sweep(cases, path=killed, resume=True, scheduler="none")
    assert again.resumed == len(cases) and pq.read_table(killed).equals(table)


def test_cli_sweep_out_parquet(tmp_path, capsys, monkeypatch):
    pytest.importorskip("pyarrow", reason="pyarrow is not installed: sweep --out *.parquet NOT checked")
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, 'name = "tiny"\n[base]\nspeed_kmh = 30.0\n[grid]\nroad = ["dry-asphalt", "snow"]\n')
    assert main(["sweep", str(spec), "--scheduler", "none", "--out", "r.parquet"]) == 0
    assert "rows in r.parquet" in capsys.readouterr().out
    assert [r.case.road for r in read_results(tmp_path / "r.parquet")] == ["dry-asphalt", "snow"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.parquet", "spec.toml"]


def test_a_parquet_results_file_without_pyarrow_is_refused_before_any_case(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "pyarrow", None)
    monkeypatch.setitem(sys.modules, "pyarrow.parquet", None)
    with pytest.raises(PrerequisiteError, match="Parquet results need pyarrow"):
        run_sweep(QUICK, path=tmp_path / "rows.parquet", scheduler="none")
    assert list(tmp_path.iterdir()) == []
    (tmp_path / "not.parquet").write_text("case_id,status\n")
    monkeypatch.undo()
    pytest.importorskip("pyarrow", reason="pyarrow is not installed: a foreign Parquet file NOT checked")
    with pytest.raises(SimulationError, match="not a readable Parquet file"):
        read_results(tmp_path / "not.parquet")


def test_case_observers_travel_as_source_and_are_used_where_installed(monkeypatch):
    import pickle

    from switchobs.codegen import CObserver
    from switchobs.loop import EstimatorSpec, _factory, install_observers, xbs_estimator
    from switchobs.plants import QuarterCar

    monkeypatch.setattr(_factory, "_INSTALLED", {})
    case = BrakingCase(observer="xbs4", beta1=80.0, beta2=120.0, impl="c", method="radau3")
    built = _run.case_observers([case, replace(case, speed_kmh=99.0), replace(case, impl="python"),
                                 BrakingCase()])
    assert len(built) == 1 and isinstance(next(iter(built.values())), CObserver)  # one setting, C only
    data = pickle.dumps(built)                     # what Client.run hands a worker: C source, no binary
    assert b"\x7fELF" not in data and b"xbs4_step" in data
    shipped = pickle.loads(data)
    assert install_observers(shipped) == 1
    spec = EstimatorSpec("xbs4", beta=80.0, beta2=120.0, impl="c", method="radau3")
    est = xbs_estimator(spec, QuarterCar(load_n=case.load_n), case.road)
    assert est.observer is next(iter(shipped.values()))
    with_installed = run_case(case).to_json()
    monkeypatch.setattr(_factory, "_INSTALLED", {})
    assert with_installed == run_case(case).to_json() and with_installed["status"] == "stopped"


def test_pareto_front_and_tuning_pick_a_non_dominated_pair():
    assert pareto_front([(1.0, 5.0), (2.0, 2.0), (3.0, 3.0), (math.inf, 0.1)]) == [0, 1]

    def row(b1, b2, rec, noise):
        return CaseResult(BrakingCase(observer="xbs4", beta1=b1, beta2=b2), "stopped",
                          {"recovery_max_s": rec, "xbs_rms_settled": noise})
    results = [row(25, 25, 1.0, 0.1), row(50, 50, 0.5, 0.2), row(100, 100, 0.2, 1.0), row(100, 50, 0.6, 0.3),
               row(200, 200, None, 0.05)]
    # a case whose road change came too late to score (no recovery_s) says nothing about re-convergence
    late = CaseResult(BrakingCase(observer="xbs4", beta1=50, beta2=50), "stopped",
                      {"recovery_s": [], "recovery_max_s": None, "xbs_rms_settled": 0.2})
    tuned = tune_betas([*results, late])
    assert tuned.pairs[1][2:] == (0.5, pytest.approx(0.2), 2)
    assert (tuned.beta1, tuned.beta2) == (50.0, 50.0)
    assert [tuned.pairs[i][:2] for i in tuned.front] == [(100.0, 100.0), (50.0, 50.0), (25.0, 25.0)]
    assert tuned.command.startswith("switchobs design abs-xbs4 --spectrum=-50,-50,-50,-50")
    table = summary_table(results, rows=["beta1"], column="observer", metric="xbs_rms_settled")
    assert table.cells[2] == (pytest.approx(0.65),) and table.counts[2] == (2,)


def test_the_example_spec_files_load():
    t41 = load_sweep_spec(ROOT / "examples" / "sweep_table41.toml")
    assert len(t41.cases) == 30 and t41.tables[0].column == "controller"
    mc = load_sweep_spec(ROOT / "examples" / "sweep_robustness.toml")
    assert len(mc.cases) == 1000 and len({c.case_id for c in mc.cases}) == 1000
    tune = load_sweep_spec(ROOT / "examples" / "sweep_tune_xbs4.toml")
    assert tune.tune and len(tune.cases) == 32
    cert = load_sweep_spec(ROOT / "examples" / "sweep_certify_load.toml")
    assert cert.kind == "certify" and cert.cases[0].box[0][0] == "a"


def _write_spec(tmp_path, text):
    path = tmp_path / "spec.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_cli_sweep_runs_in_process_prints_tables_and_tunes(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, """
name = "tiny"
[base]
observer = "xbs4"
speed_kmh = 40.0
changes = [["wet-asphalt", 0.4]]
[grid]
beta1 = [60.0, 120.0]
[[table]]
rows = ["beta1"]
column = "road"
metric = "xbs_rms_settled"
[[heatmap]]
x = "beta1"
y = "road"
metric = "stopping_distance_m"
[tune]
""")
    assert main(["sweep", str(spec), "--scheduler", "none", "--plots", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "sweep 'tiny': 2 braking cases" in out and "mean xbs_rms_settled" in out
    assert "switchobs design abs-xbs4 --spectrum=" in out and "<- chosen" in out
    assert (tmp_path / "tiny.jsonl").is_file() and (tmp_path / "pareto.png").is_file()
    assert (tmp_path / "heatmap-stopping_distance_m-road-beta1.png").is_file()
    assert main(["sweep", str(spec), "--scheduler", "none"]) == 2
    assert "exists; resume it (--resume)" in capsys.readouterr().err
    assert main(["sweep", str(spec), "--scheduler", "none", "--resume", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["sweep"]["resumed"] == 2 and data["tuned"]["beta1"] in (60.0, 120.0)


@pytest.mark.parametrize("text, match", [
    ('kind = "simulate"', "kind must be 'braking' or 'certify'"),
    ('[base]\nroad = "mud"', "unknown road 'mud'"),
    ('[grid]\nspeed_kmh = {start = 10}', r"grid.speed_kmh: an axis is a non-empty list"),
    ('[monte_carlo]\ncount = 2\n[monte_carlo.draw]\nspeed_kmh = {normal = [1, 2]}', "not an admissible draw"),
    ('colour = "red"', r"unknown key\(s\) \['colour'\]"),
    ('name = ', "is not valid TOML"),
    ('[base]\nobserver = "xbs4"\n[tune]', r"tuning needs beta1 \(and beta2\) in every case"),  # before running
    ('[monte_carlo]\ncount = 2\n[monte_carlo.draw]\nspeed_kmh = {uniform = [40, 30]}',
     r"monte_carlo.draw.speed_kmh: a uniform draw needs low <= high, got \[40, 30\]"),
    ('[monte_carlo]\ncount = 2\n[monte_carlo.draw]\nspeed_kmh = {uniform = [30, inf]}',
     r"a uniform draw: high must be a finite number, got inf"),
    ('[monte_carlo]\ncount = 2\n[monte_carlo.draw]\nchanges = {roads = ["snow"], count = [1, 1], window_s = [2, 1]}',
     r"window_s = \[t0, t1\] with 0 <= t0 <= t1, got \[2, 1\]"),
    ('[monte_carlo]\ncount = 2\n[monte_carlo.draw]\nencoder_seed = {integers = [5, 1]}',
     r"an integer draw needs low <= high, got \[5, 1\]"),
    ('[monte_carlo]\ncount = true', r"monte_carlo.count must be an integer >= 1, got True"),
    ('name = 3', r"name must be a text, got 3"),
    ('[grid]\nspeed_kmh = {start = "a", stop = 2, num = 3}', r"grid.speed_kmh: .*start must be a finite number"),
    ('[base]\nchanges = 3', r"changes is a list of at most 100 \(road, time_s\) pairs"),
    ('kind = "certify"\n[grid]\n"../x" = [1.0]', r"'../x' is not a name"),
    ('kind = "certify"\n[base]\nspectrum = "-beta1,-bogus"\n[grid]\nbeta1 = [1.0]',
     r"spectrum '-beta1,-bogus': spectrum pole '-bogus': unknown name 'bogus'"),
    ('kind = "certify"\n[base]\nspectrum = "-beta1,1/0"\n[grid]\nbeta1 = [1.0]',
     r"spectrum pole '1/0': the value is zoo \(a division by zero"),  # refused where it is parsed
])
def test_cli_sweep_refuses_bad_spec_files_in_one_line(tmp_path, capsys, text, match):
    spec = _write_spec(tmp_path, text)
    assert main(["sweep", str(spec), "--scheduler", "none", "--out", str(tmp_path / "x.jsonl")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert __import__("re").search(match, err), err
    assert not (tmp_path / "x.jsonl").exists()


def test_missing_dask_is_a_prerequisite_error_and_serial_runs_still_work(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(PrerequisiteError, match=r'pip install "switchobs\[sweep\]".*--scheduler none'):
        run_sweep(QUICK[:1], scheduler="local")
    assert run_sweep(QUICK[:1], scheduler="none").results[0].ok


# ----------------------------------------------------------------------------- on a Dask LocalCluster

def _bit_identical_on_a_worker(client):
    cases = [BrakingCase(road="dry-asphalt", speed_kmh=50.0, changes=(("snow", 0.5),), observer="xbs4",
                         beta1=100.0, beta2=150.0, encoder_ppr=60, encoder_seed=5, duration_s=1.2),
             BrakingCase(road="wet-asphalt", speed_kmh=40.0, observer="adaptive", controller="two-phase")]
    remote = run_sweep(cases, scheduler=client, batch_size=1)
    assert remote.engine.startswith("Dask client")
    local = [run_case(c) for c in cases]
    assert [r.to_json() for r in remote.results] == [r.to_json() for r in local]
    assert remote.results[0].metrics["xbs_rms"] == local[0].metrics["xbs_rms"]  # the same float, not close


def _workers_take_the_c_observers_built_here(client):
    """The warm-up: the C observer is built in this process and installed on both workers, whose cases then
    give the in-process numbers (the same C source, compiled or found in the worker's own cache)."""
    from switchobs.loop import _factory

    case = BrakingCase(road="wet-asphalt", speed_kmh=40.0, observer="xbs4", beta1=70.0, beta2=90.0, impl="c",
                       method="radau3", encoder_ppr=60, stop_kmh=10.0, duration_s=0.6)
    remote = run_sweep([case, replace(case, speed_kmh=45.0)], scheduler=client, batch_size=1)
    installed = client.run(lambda: sorted(k[:3] for k in _factory._INSTALLED))
    assert len(installed) == 2 and all(("xbs4", 70.0, 90.0) in keys for keys in installed.values())
    local = [run_case(c) for c in (case, replace(case, speed_kmh=45.0))]
    assert [r.to_json() for r in remote.results] == [r.to_json() for r in local]
    assert remote.results[0].ok and remote.results[0].metrics["xbs_rms"] is not None


def _table41_through_the_engine(client):
    spec = load_sweep_spec(ROOT / "examples" / "sweep_table41.toml")
    cases = [c for c in spec.cases if c.speed_kmh in (60.0, 120.0) and c.road in ("dry-asphalt", "wet-cobblestones")]
    sweep = run_sweep(cases, scheduler=client)
    by = {(r.case.speed_kmh, r.case.road, r.case.controller): r for r in sweep.results}
    reference = table41(roads=("dry-asphalt", "wet-cobblestones"), speeds_kmh=(60.0, 120.0))
    assert len(reference.rows) == 4 and len(by) == 8
    for row in reference.rows:
        five, two = by[(row.speed_kmh, row.road, "five-phase")], by[(row.speed_kmh, row.road, "two-phase")]
        assert (five.metrics["braking_distance_m"], two.metrics["braking_distance_m"]) == \
            (row.five_phase_m, row.two_phase_m)
        assert (five.metrics["stopping_distance_m"], two.metrics["stopping_distance_m"]) == \
            (row.five_phase_stopping_m, row.two_phase_stopping_m)
        assert (five.status, two.status) == (row.five_phase_status, row.two_phase_status)


def _a_killed_worker_does_not_lose_the_sweep(client, path):
    # a Python observer that the two-phase ABS reads keeps these brakings in the Python loop (a few tenths of a
    # second each), so that a task is seen running before the sweep ends; without one the compiled loop
    # finishes them in milliseconds
    cases = grid(BrakingCase(observer="xbs4", controller="two-phase"),
                 road=["dry-asphalt", "wet-asphalt", "dry-concrete", "snow"], speed_kmh=[100.0, 120.0])
    pids = client.run(os.getpid)
    out: dict = {}
    runner = threading.Thread(target=lambda: out.setdefault("sweep", run_sweep(
        cases, path=path, scheduler=client, batch_size=1)))
    runner.start()
    deadline = time.monotonic() + 120
    while not any(client.processing().values()) and runner.is_alive() and time.monotonic() < deadline:
        time.sleep(0.02)
    victim = next((w for w, tasks in client.processing().items() if tasks), None)
    assert victim is not None, "no task was seen running: the sweep ended before a worker could be killed"
    os.kill(pids[victim], signal.SIGKILL)  # the nanny restarts it; the scheduler re-runs its task elsewhere
    runner.join(timeout=600)
    sweep = out["sweep"]
    assert [r.status for r in sweep.results] == ["stopped"] * len(cases)
    assert [r.to_json() for r in sweep.results] == [r.to_json() for r in read_results(path)]


@pytest.mark.slow
def test_on_one_dask_local_cluster(tmp_path):
    """Bit-identical metrics on a worker, Table 4.1 cells, a killed worker: one cluster for the three checks
    (under pytest-xdist every worker process running a cluster test would start its own)."""
    distributed = pytest.importorskip("distributed")
    import logging

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0",
                                  silence_logs=logging.ERROR) as cluster, distributed.Client(cluster) as client:
        _bit_identical_on_a_worker(client)
        _workers_take_the_c_observers_built_here(client)
        _table41_through_the_engine(client)
        _a_killed_worker_does_not_lose_the_sweep(client, tmp_path / "rows.jsonl")


# ----------------------------------------------------------------------------- hostile specs and options

#: One short braking (about 0.3 s simulated): the cheapest case that runs through the engine.
TINY = '[base]\nspeed_kmh = 10.0\n'


@pytest.mark.parametrize("name", ["../../evil", "/ABSOLUTE/evil", "a/b/c", "a\\u0000b", "é" * 300, "x" * 5000, "..",
                                  "", ".hidden", "-rf", "C:\\\\evil"])
def test_a_spec_name_never_writes_outside_the_current_directory(tmp_path, monkeypatch, capsys, name):
    cwd = tmp_path / "a" / "b"
    cwd.mkdir(parents=True)
    monkeypatch.chdir(cwd)
    (tmp_path / "ABSOLUTE").mkdir()
    name = name.replace("/ABSOLUTE", str(tmp_path / "ABSOLUTE"))
    spec = _write_spec(tmp_path, f'name = "{name}"\n' + TINY)
    before = sorted(p for p in tmp_path.rglob("*") if not p.is_relative_to(cwd))
    assert main(["sweep", str(spec), "--scheduler", "none", "-q"]) == 0, capsys.readouterr().err
    assert sorted(p for p in tmp_path.rglob("*") if not p.is_relative_to(cwd)) == before
    written = list(cwd.iterdir())
    assert len(written) == 1 and written[0].suffix == ".jsonl" and len(written[0].name) <= 106
    assert set(written[0].name) <= set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-")
    assert f"rows in {written[0].name}" in capsys.readouterr().out


@pytest.mark.parametrize("names", [("../../x", "y", "m"), ("x", "/etc/y", "m\x00"), ("é", "..", "")])
def test_heatmap_file_names_are_plain_file_names(names):
    from switchobs.sweep._spec import HeatmapSpec

    name = HeatmapSpec(*names).filename
    assert "/" not in name and "\x00" not in name and not name.startswith(".") and name.endswith(".png")
    assert Path(name).name == name and name.isascii()


#: Sweeps far beyond the limits, each refused from the spec in well under a second (nothing built or run).
HUGE = [
    ('[monte_carlo]\ncount = 1000000\n[monte_carlo.draw]\nspeed_kmh = {uniform = [10, 20]}', [],
     r"cases of the sweep \(1000000 Monte-Carlo draws\): about 1e\+06, above the limit of 1e\+05"),
    ('[grid]\nspeed_kmh = {start = 10, stop = 20, num = 1000000}\nload_n = {start = 2000, stop = 3000, '
     'num = 1000000}', [], r"grid 1e\+06 x 1e\+06\): about 1e\+12"),
    ('[grid]\nspeed_kmh = {start = 10, stop = 20, step = 1e-300}', [], r"grid 1e\+301\): about 1e\+301"),
    ('[grid]\nspeed_kmh = {start = -1e308, stop = 1e308, step = 1e-300}', [], r"about inf, above the limit"),
    ('[monte_carlo]\ncount = 1\n[monte_carlo.draw]\nchanges = {roads = ["snow"], count = [1000000, 1000000], '
     'window_s = [0.5, 2.0]}', [], r"count_min must be an integer in \[0, 100\] \(MAX_ROAD_CHANGES\), got 1000000"),
    (TINY + '[grid]\nload_n = [2000.0, 2500.0, 3000.0]', ["--max-cases", "2"], r"about 3, above the limit of 2"),
    ('[base]\ndt_s = 1e-6\n[grid]\nspeed_kmh = {start = 10, stop = 20, num = 20}', [],
     r"integration steps of the 20 braking cases .*: about 1\.2e\+09, above the limit of 1e\+09.*--max-steps"),
    (TINY, ["--workers", "100000", "--scheduler", "local"], r"worker processes of the local cluster .*above the "
                                                            r"limit of \d+; give at most 4 per core"),
]


@pytest.mark.parametrize("text, options, match", HUGE)
def test_sweeps_beyond_the_limits_are_refused_before_any_case(tmp_path, capsys, monkeypatch, text, options, match):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(_engine, "run_case", lambda *a, **k: pytest.fail("a case ran"))
    spec = _write_spec(tmp_path, text)
    start = time.perf_counter()
    assert main(["sweep", str(spec), "--scheduler", "none", *options]) == 2
    err = capsys.readouterr().err
    assert time.perf_counter() - start < 5 and err.count("\n") == 1 and "Traceback" not in err
    assert __import__("re").search(match, err), err
    assert [p.name for p in tmp_path.iterdir()] == ["spec.toml"]


def test_the_limits_can_be_raised(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, TINY + '[grid]\nload_n = [2000.0, 2500.0, 3000.0]')
    assert main(["sweep", str(spec), "--scheduler", "none", "--max-cases", "2"]) == 2
    assert main(["sweep", str(spec), "--scheduler", "none", "--max-cases", "3", "--max-steps", "1.8e5"]) == 0
    assert "sweep: 3 cases" in capsys.readouterr().out
    with pytest.raises(SimulationError, match=r"about 3, above the limit of 2"):
        grid(BrakingCase(), load_n=[2000.0, 2500.0, 3000.0], max_cases=2)


#: Tables and heatmaps that could only print dashes, or fail once every case ran: refused from the spec.
VIEWS = [
    ('[[table]]\nrows = ["road"]\ncolumn = "speed"\nmetric = "braking_distance_m"',
     r"\[\[table\]\] 1: braking cases have no field 'speed'; fields: beta1, "),
    ('[[table]]\nrows = ["road"]\ncolumn = "speed_kmh"\nmetric = "bogus"',
     r"\[\[table\]\] 1: 'bogus' is not a number of braking rows.*choose one of braking_distance_m"),
    ('[[table]]\nrows = ["road"]\ncolumn = "speed_kmh"\nmetric = "segments"', r"'segments' is not a number"),
    ('[[heatmap]]\nx = "case_id"\ny = "road"\nmetric = "stop_time_s"', r"\[\[heatmap\]\] 1: .*no field 'case_id'"),
    ('[[heatmap]]\nx = "speed_kmh"\ny = "road"\nmetric = "xbs_rms"',
     r"metric 'xbs_rms' exists only for cases that set observer, and every case has observer = 'none'"),
    ('table = 3', r"table must be a list of tables \(\[\[table\]\]\), got 3"),
]


@pytest.mark.parametrize("text, match", VIEWS)
def test_tables_and_heatmaps_are_checked_before_the_first_case(tmp_path, capsys, monkeypatch, text, match):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(_engine, "run_case", lambda *a, **k: pytest.fail("a case ran"))
    spec = _write_spec(tmp_path, text + "\n" + TINY)
    assert main(["sweep", str(spec), "--scheduler", "none"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and __import__("re").search(match, err), err
    assert [p.name for p in tmp_path.iterdir()] == ["spec.toml"]


def test_the_numeric_metrics_are_those_run_case_returns():
    braking = run_case(BrakingCase(road="dry-asphalt", speed_kmh=30.0, changes=(("wet-asphalt", 0.2),),
                                   observer="xbs4"))
    assert braking.ok and set(_run.NUMERIC_METRICS["braking"]) <= set(braking.metrics)
    assert all(braking.metrics[k] is None or isinstance(braking.metrics[k], (int, float))
               for k in _run.NUMERIC_METRICS["braking"])
    certify = run_case(CertifyCase(betas=(("beta1", 100.0), ("beta2", 150.0)), discrete="radau3"))
    numbers = {k for k, need in _run.NUMERIC_METRICS["certify"].items() if need != "box"}
    assert certify.ok and numbers <= set(certify.metrics)
    assert certify.metrics["certified"] is True and certify.metrics["dwell_time_value"] is None  # dwell "any"
    assert all(v is None or isinstance(v, (bool, float)) for v in map(certify.metrics.get, numbers))
    # the metrics that are not numbers are the ones a table cannot average
    assert {"verdict", "spectrum"} <= set(certify.metrics) - set(_run.NUMERIC_METRICS["certify"])


class _Unreachable:
    def __init__(self, *args, **kwargs):
        raise OSError("Timed out trying to connect to tcp://127.0.0.1:1 after 20 s")


@pytest.mark.parametrize("how", ["bogus", "unreachable", "no dask", "cluster fails"])
def test_a_sweep_that_cannot_start_leaves_no_file(tmp_path, capsys, monkeypatch, how):
    distributed = pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, 'name = "s"\n' + TINY)
    scheduler = {"bogus": "bogus", "unreachable": "tcp://127.0.0.1:1"}.get(how, "local")
    if how == "unreachable":  # the real connection attempt waits 20 s: the same OSError, at once
        monkeypatch.setattr(distributed, "Client", _Unreachable)
    if how == "no dask":
        monkeypatch.setitem(sys.modules, "distributed", None)
    if how == "cluster fails":
        monkeypatch.setattr(distributed, "LocalCluster", lambda *a, **k: (_ for _ in ()).throw(
            RuntimeError("Worker failed to start")))
    assert main(["sweep", str(spec), "--scheduler", scheduler, "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err and err.startswith("switchobs sweep: error: ")
    assert [p.name for p in tmp_path.iterdir()] == ["spec.toml"]


def test_resume_refuses_another_study_s_results_file(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    other = _write_spec(tmp_path, '[base]\nspeed_kmh = 12.0\n')
    assert main(["sweep", str(other), "--scheduler", "none", "--out", "rows.jsonl", "-q"]) == 0
    before = (tmp_path / "rows.jsonl").read_bytes()
    spec = _write_spec(tmp_path, TINY + '[grid]\nroad = ["dry-asphalt", "snow"]')
    capsys.readouterr()
    assert main(["sweep", str(spec), "--scheduler", "none", "--out", "rows.jsonl", "--resume"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "holds 1 row(s) of cases that are not in this sweep" in err
    assert (tmp_path / "rows.jsonl").read_bytes() == before
    # a study whose cases are all in this sweep is a killed run of it: its rows are kept
    first = _write_spec(tmp_path, TINY)
    assert main(["sweep", str(first), "--scheduler", "none", "--out", "sub.jsonl", "-q"]) == 0
    capsys.readouterr()
    assert main(["sweep", str(spec), "--scheduler", "none", "--out", "sub.jsonl", "--resume", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["sweep"]["resumed"] == 1


def test_case_warnings_and_c_output_do_not_reach_the_user(tmp_path, capfd, monkeypatch):
    import warnings

    real = _engine.run_case

    def noisy(case, **kwargs):
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        os.write(1, b"KKT matrix has < n positive eigenvalues\n")  # what a C solver prints, past Python
        os.write(2, b"ERROR: init_lin_sys_work failure\n")
        return real(case, **kwargs)
    monkeypatch.setattr(_engine, "run_case", noisy)
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, TINY + '[grid]\nroad = ["dry-asphalt", "snow"]')
    for flags in (["-q"], ["--json"]):
        assert main(["sweep", str(spec), "--scheduler", "none", "--out", f"{flags[0].strip('-')}.jsonl", *flags]) == 0
        out, err = capfd.readouterr()
        assert err == "" and "KKT" not in out
    assert json.loads(out)["sweep"]["cases"] == 2


def test_a_failed_case_gives_exit_1_and_one_failed_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = _write_spec(tmp_path, '[base]\nspeed_kmh = 2.0\n[[heatmap]]\nx = "speed_kmh"\ny = "road"\n'
                                 'metric = "stop_time_s"')  # below the stop speed: the case raises
    (tmp_path / "figures").mkdir()
    assert main(["sweep", str(spec), "--scheduler", "none", "--plots", "figures"]) == 1
    err = capsys.readouterr().err
    assert err == "switchobs sweep: failed: 1 of 1 cases failed (their rows in spec.jsonl hold the errors)\n"
    assert list((tmp_path / "figures").iterdir()) == []  # nothing to draw, and no partial folder


@pytest.mark.slow
def test_ctrl_c_during_a_dask_sweep_is_one_line_and_exit_130(tmp_path):
    """The terminal sends SIGINT to every process of the command: the workers must not print tracebacks."""
    import subprocess

    pytest.importorskip("distributed")
    spec = _write_spec(tmp_path, '[base]\nobserver = "xbs4"\ncontroller = "two-phase"\n[grid]\n'
                                 'speed_kmh = {start = 100, stop = 200, num = 40}\nroad = ["dry-asphalt", "snow"]')
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "PYTHONPATH": str(ROOT / "src")}
    proc = subprocess.Popen([sys.executable, "-m", "switchobs", "sweep", str(spec), "--workers", "1",
                             "--batch-size", "1", "--out", str(tmp_path / "rows.jsonl")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    deadline = time.monotonic() + 240
    while not (tmp_path / "rows.jsonl").exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)  # until the workers run cases
    assert proc.poll() is None, proc.communicate()
    os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C: the whole process group
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and err == "switchobs sweep: interrupted\n", err
    rows = read_results(tmp_path / "rows.jsonl")  # the finished cases are kept for --resume
    assert rows and all(r.ok for r in rows)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:  # no worker left behind (they exit once the cluster closes)
        try:
            os.killpg(proc.pid, 0)
        except ProcessLookupError:
            break
        time.sleep(0.2)
    else:
        left = subprocess.run(["ps", "-o", "pid,stat,etime,cmd", "-g", str(proc.pid)], capture_output=True, text=True)
        pytest.fail(f"processes of the sweep still run 20 s after it ended:\n{left.stdout}")


def test_the_sweeps_page_names_the_numeric_metrics_and_the_limits():
    from switchobs import _limits

    page = (ROOT / "docs" / "sweeps.md").read_text("utf-8")
    paragraph = page.split("A table or heatmap averages", 1)[1].split("(`switchobs.sweep._run.NUMERIC_METRICS`)")[0]
    assert set(__import__("re").findall(r"`(\w+)`", paragraph)) == {
        name for metrics in _run.NUMERIC_METRICS.values() for name in metrics}
    named = set(__import__("re").findall(r"`(MAX_\w+)`", page))
    assert named == {"MAX_SWEEP_CASES", "MAX_SWEEP_STEPS", "MAX_WORKERS_PER_CORE", "MAX_ROAD_CHANGES"}
    assert named <= set(_limits.LIMITS)
