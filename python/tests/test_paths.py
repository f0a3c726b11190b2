"""Relative data paths from Python read the file the CLI reads (issue 30, att30n-3, -4, -10,
-11): a scenario read from a file keeps its folder (absolute, taken when it was read) through a
chdir, the file's removal, pickling and derived scenarios; a sweep's row is re-run from
`sweep_base` with its cells as they are; a sweep's unreadable data file is refused before any
run. Each check runs next to decoy files that the wrong base would read without a word."""

import os
import pickle
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]

# The metric columns, as test_api.py states them (one list for both files).
from test_api import METRICS  # noqa: E402

OLD_PATH = '"../data/no2_germany_kriged/no2_germany_kriged.csv"'


@pytest.fixture
def tree(tmp_path):
    """tmp/w/sc/x.toml reads ../data/a.csv (the kriged NO2 map); tmp/w/data/b.csv is the same
    map 1.5 higher (the level-10 isoline moves); tmp/w/sc/y.toml names b.csv itself (the
    independent computation). Decoys, copies of a.csv, where a wrong base would find
    ../data/b.csv: tmp/data/b.csv (from the working directory tmp/w) and
    tmp/w/far/x/data/b.csv (from tmp/w/far/x, which also has a copy of sc/)."""
    src = (ROOT / "scenarios" / "paper-fig2a-field.toml").read_text()
    assert OLD_PATH in src
    data = (ROOT / "data" / "no2_germany_kriged" / "no2_germany_kriged.csv").read_text()
    shifted = "\n".join(",".join(repr(float(v) + 1.5) for v in line.split(",")) for line in data.splitlines()) + "\n"
    w = tmp_path / "w"
    for d in ["sc", "data", "far/x/sc", "far/x/data", "empty"]:
        (w / d).mkdir(parents=True)
    (tmp_path / "data").mkdir()
    (w / "data" / "a.csv").write_text(data)
    (w / "data" / "b.csv").write_text(shifted)
    (w / "sc" / "x.toml").write_text(src.replace(OLD_PATH, '"../data/a.csv"'))
    (w / "sc" / "y.toml").write_text(src.replace(OLD_PATH, '"../data/b.csv"'))
    (tmp_path / "data" / "b.csv").write_text(data)
    (w / "far" / "x" / "data" / "b.csv").write_text(data)
    (w / "far" / "x" / "data" / "a.csv").write_text(data)
    shutil.copy(w / "sc" / "x.toml", w / "far" / "x" / "sc" / "x.toml")
    return w


def reference(w):
    """The run on b.csv from a scenario file that names it (10 s), and the run on a.csv."""
    on_b = isotrack.Scenario.from_file(str(w / "sc" / "y.toml")).set("sim.duration_s", 10.0).run(record_rate_hz=0.0)
    on_a = isotrack.Scenario.from_file(str(w / "sc" / "x.toml")).set("sim.duration_s", 10.0).run(record_rate_hz=0.0)
    assert any(on_a.summary[m] != on_b.summary[m] for m in METRICS)  # the file decides
    return on_b.summary


def same_run(summary, want, w):
    assert list(summary["data_files"]) == [str((w / "data" / "b.csv").resolve())], summary["data_files"]
    for m in METRICS:
        assert summary[m] == want[m], (m, summary[m], want[m])


def test_from_file_keeps_its_folder_through_a_chdir_and_the_files_removal(tree, monkeypatch):
    """att30n-4: `Scenario.from_file("sc/x.toml")` (relative), then `os.chdir`, then
    `.set("field.path", "../data/b.csv")` read the path against the new directory's copy of
    `sc/` (a decoy, without a word) or, without one, against the new working directory."""
    w = tree
    want = reference(w)
    monkeypatch.chdir(w)
    s = isotrack.Scenario.from_file("sc/x.toml").set("sim.duration_s", 10.0)
    same_run(s.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    monkeypatch.chdir(w / "far" / "x")  # its sc/ and data/b.csv are decoys
    same_run(s.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    monkeypatch.chdir(w / "empty")  # no sc/ here: it fell back to the working directory
    same_run(s.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    # Derived scenarios (a set, a run's flown scenario) keep the folder too.
    derived = s.set("controller.kp", 10.0).run(record_rate_hz=0.0).scenario
    same_run(derived.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    # The scenario file removed after it was read: its folder is still the one it was in.
    monkeypatch.chdir(w)
    (w / "sc2").mkdir()
    shutil.copy(w / "sc" / "x.toml", w / "sc2" / "x.toml")
    t = isotrack.Scenario.from_file("sc2/x.toml").set("sim.duration_s", 10.0)
    os.remove(w / "sc2" / "x.toml")
    monkeypatch.chdir(w / "far" / "x")
    same_run(t.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)


def test_a_pickled_scenario_keeps_its_folder(tree, monkeypatch):
    """att30n-11: a scenario read from a file lost its folder when pickled: the same
    `.set("field.path", "../data/b.csv")` in the unpickled copy read the path against the
    working directory (here the decoy tmp/data/b.csv)."""
    w = tree
    want = reference(w)
    monkeypatch.chdir(w)
    s = isotrack.Scenario.from_file("sc/x.toml").set("sim.duration_s", 10.0)
    for copy in [pickle.loads(pickle.dumps(s)), pickle.loads(pickle.dumps(pickle.loads(pickle.dumps(s))))]:
        same_run(copy.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    # Unpickled after a chdir (a worker that changed its directory).
    blob = pickle.dumps(s.set("controller.kp", 10.0))
    monkeypatch.chdir(w / "far" / "x")
    u = pickle.loads(blob)
    same_run(u.set("field.path", "../data/b.csv").run(record_rate_hz=0.0).summary, want, w)
    # Scenarios without a file keep reading against the working directory, pickled or not.
    d = pickle.loads(pickle.dumps(isotrack.Scenario.from_toml(s.to_toml())))
    with pytest.raises(isotrack.ScenarioError, match="cannot read"):
        d.set("field.path", "../nowhere/b.csv")


def test_a_spawned_worker_reads_the_parents_file(tree):
    """att30n-11 as README uses pickling: a `multiprocessing` spawn worker gets the scenario
    and sets a relative path: it reads the file the parent reads (it read the decoy
    tmp/data/b.csv, the worker's ../data from the working directory)."""
    w = tree
    want = reference(w)
    script = w / "spawn.py"
    script.write_text(
        "import json, multiprocessing as mp\n"
        "from isotrack import Scenario\n"
        "def work(sc):\n"
        "    r = sc.set('field.path', '../data/b.csv').run(record_rate_hz=0.0)\n"
        "    return json.dumps(r.summary)\n"
        "if __name__ == '__main__':\n"
        "    s = Scenario.from_file('sc/x.toml').set('sim.duration_s', 10.0)\n"
        "    with mp.get_context('spawn').Pool(1) as p:\n"
        "        print(p.apply(work, (s,)))\n"
    )
    r = subprocess.run([sys.executable, str(script)], cwd=w, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    import json

    same_run(json.loads(r.stdout), want, w)


def test_a_sweep_row_with_relative_paths_is_rerun_from_sweep_base(tree, monkeypatch):
    """att30n-3: README's Python re-run of a row of `isotrack.sweep(...)` whose `field.path`
    cell is relative (to the sweep file's folder) read another file when set on the sweep's
    `scenario` file (against that file's folder). `isotrack.sweep_base(SWEEP)` reads the cells
    as the sweep does: every row's metrics come back bit for bit, next to two decoys (the
    scenario folder's ../x.csv and the working directory's ../x.csv, copies of a.csv)."""
    w = tree
    deeper = w / "sweeps" / "deeper"
    deeper.mkdir(parents=True)
    shutil.copy(w / "data" / "b.csv", w / "sweeps" / "x.csv")  # the cell's file: ../x.csv from deeper/
    shutil.copy(w / "data" / "a.csv", w / "x.csv")  # decoy 1: sc/../x.csv
    (w / "far" / "q").mkdir()
    shutil.copy(w / "data" / "a.csv", w / "far" / "x.csv")  # decoy 2: the cwd far/q's ../x.csv
    sw = deeper / "p3.toml"
    sw.write_text(
        'scenario = "../../sc/x.toml"\n[base]\nsim.duration_s = 10.0\n'
        '[grid]\nfield.path = ["../x.csv", "../../data/a.csv"]\ncontroller.kp = [5.0, 10.0]\n'
    )
    monkeypatch.chdir(w / "far" / "q")
    cols = isotrack.sweep(str(sw))
    assert list(cols["outcome"]) == ["completed"] * 4
    assert sorted(cols["field.path"].tolist()) == ["../../data/a.csv"] * 2 + ["../x.csv"] * 2
    base = isotrack.sweep_base(str(sw))
    monkeypatch.chdir(w / "far" / "x")  # anywhere: the folder was taken when the sweep was read
    for i in range(4):
        row = {k: cols[k][i].item() for k in ["field.path", "controller.kp", "sim.seed"]}
        r = base.set(row).run(record_rate_hz=0.0).summary
        for m in METRICS:
            got, want = r[m], cols[m][i].item()
            assert got == want or (got is None and want != want), (i, m, got, want)
        read = (w / "sweeps" / "x.csv") if row["field.path"] == "../x.csv" else (w / "data" / "a.csv")
        assert list(r["data_files"]) == [str(read.resolve())]
    # The rows on ../x.csv (b's map) differ from those on a.csv at the same gain: a decoy
    # (a copy of a.csv) read instead would show.
    for kp in (5.0, 10.0):
        on = {p: cols["steady_state_rms_error"][i] for i, p in enumerate(cols["field.path"]) if cols["controller.kp"][i] == kp}
        assert on["../x.csv"] != on["../../data/a.csv"], on


@pytest.mark.parametrize("bad", ["nowhere.csv", "dir.csv", "fifo.csv"])
def test_sweep_refuses_an_unreadable_grid_data_file_before_any_run(tree, bad):
    """att30n-10: `isotrack sweep` exits 66 before any run for a [grid] data file it cannot
    read; Python's `sweep` ran the sweep, those rows `invalid_scenario`, no exception. Now a
    FileNotFoundError naming the file and the keys, and no run (a controller factory is never
    called; a FIFO is never opened, so never waited on)."""
    w = tree
    (w / "bad").mkdir()
    (w / "bad" / "dir.csv").mkdir()
    os.mkfifo(w / "bad" / "fifo.csv")
    (w / "sweeps").mkdir()
    sw = w / "sweeps" / "pg.toml"
    sw.write_text(
        'scenario = "../sc/x.toml"\n[base]\nsim.duration_s = 5.0\n'
        f'[grid]\nfield.path = ["../data/a.csv", "../bad/{bad}"]\ncontroller.kp = [5.0, 10.0]\n'
    )
    calls = []

    def factory(sc):
        calls.append(sc)
        return None

    for kwargs in [{}, {"controller_factory": factory}]:
        with pytest.raises(FileNotFoundError) as e:
            isotrack.sweep(str(sw), **kwargs)
        # The key and the value as the sweep file writes them (att30n-13: `[grid] field.path
        # value 2 "../bad/..."`).
        assert bad in str(e.value) and '[grid] field.path value 2 "../bad/' in str(e.value), str(e.value)
    with pytest.raises(FileNotFoundError, match=bad):
        isotrack.sweep_base(str(sw))
    assert calls == []
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if Path(exe).exists():  # the CLI says 66 for the same file
        r = subprocess.run([exe, "sweep", str(sw), "--out", str(w / "o")], capture_output=True, text=True, timeout=120)
        assert r.returncode == 66, r.stderr


def test_random_holds_no_file_path(tree):
    """att30n-10's README half: `[random]` draws numbers only (README said a relative file path
    could stand in it): a path there is refused as the sweep's error."""
    w = tree
    (w / "sweeps").mkdir()
    sw = w / "sweeps" / "r.toml"
    sw.write_text('scenario = "../sc/x.toml"\n[random]\nruns = 2\nseed = 1\nfield.path = "../data/a.csv"\n')
    with pytest.raises(isotrack.ScenarioError, match="uniform"):
        isotrack.sweep(str(sw))


def test_a_field_paths_row_is_rerun_by_the_readmes_recipes(tree, monkeypatch):
    """att30n-12: a sweep over `field.paths` (a list) stores its cells as `field.paths[0]`,
    `field.paths[1]` columns; README's CLI recipe said one `--set` per varied column, and
    `--set field.paths[0]=...` is no key (65). README now says: set the key once to the list
    of its cells, each an absolute path (the sweep file's folder joined with the cell); from
    Python, `sweep_base(SWEEP).set("field.paths", [cells])` with the cells as they are. Both
    give every row's metrics back, bit for bit."""
    import csv
    import json

    w = tree
    src = (w / "sc" / "x.toml").read_text()
    assert 'path = "../data/a.csv"' in src
    (w / "sc" / "ts.toml").write_text(
        src.replace('path = "../data/a.csv"', 'paths = ["../data/a.csv", "../data/b.csv"]\nframe_times_s = [0.0, 10.0]')
    )
    (w / "sweeps").mkdir()
    sw = w / "sweeps" / "tp.toml"
    sw.write_text(
        'scenario = "../sc/ts.toml"\n[base]\nsim.duration_s = 10.0\n'
        '[grid]\nfield.paths = [["../data/a.csv", "../data/b.csv"], ["../data/b.csv", "../data/a.csv"]]\n'
        "controller.kp = [5.0, 10.0]\n"
    )
    monkeypatch.chdir(w / "far" / "x")  # its ../data/ is no sweeps/../data/
    cols = isotrack.sweep(str(sw))
    assert list(cols["outcome"]) == ["completed"] * 4
    base = isotrack.sweep_base(str(sw))
    for i in range(4):
        paths = [cols["field.paths[0]"][i].item(), cols["field.paths[1]"][i].item()]
        r = base.set({"field.paths": paths, "controller.kp": cols["controller.kp"][i].item(), "sim.seed": cols["sim.seed"][i].item()})
        s = r.run(record_rate_hz=0.0).summary
        for m in METRICS:
            assert s[m] == cols[m][i].item() or (s[m] is None and cols[m][i] != cols[m][i]), (i, m)
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe}")
    out = w / "o"
    r = subprocess.run([exe, "sweep", str(sw), "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    with open(out / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4
    for row in rows:
        abs_paths = [str(w / "sweeps" / row[f"field.paths[{k}]"]) for k in (0, 1)]
        d = w / f"rr{row['run_id']}"
        args = [exe, "run", str(out / "base_scenario.toml"), "--set", f"controller.kp={row['controller.kp']}"]
        args += ["--set", "field.paths=" + json.dumps(abs_paths), "--set", f"sim.seed={row['sim.seed']}"]
        r = subprocess.run(args + ["--out", str(d), "--quiet"], capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, r.stderr
        s = json.loads((d / "summary.json").read_text())
        for m in METRICS:
            if row[m] == "":
                assert s[m] is None, (row["run_id"], m)
            else:
                assert s[m] == (int(row[m]) if m == "samples" else float(row[m])), (row["run_id"], m, s[m], row[m])
    # The split column is no key: README says so.
    r = subprocess.run(
        [exe, "run", str(out / "base_scenario.toml"), "--set", f'field.paths[0]="{abs_paths[0]}"', "--out", str(w / "bad")],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 65, r.stderr
