"""Issue 30: `Run.save`, the Python door of `isotrack run --out`: it answers Ctrl-C while it
copies and writes a multi-million-row trace (leaving no half-written run directory), and it
takes the directory's lock `run --out` takes (att30c-6), in both directions."""

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

import isotrack

ROOT = Path(__file__).resolve().parents[2]
RUN_FILES = ["scenario.toml", "summary.json", "trace.csv"]


def cli() -> str:
    """The isotrack binary: $ISOTRACK_BIN, or the workspace's release build."""
    exe = os.environ.get("ISOTRACK_BIN", str(ROOT / "target" / "release" / "isotrack"))
    if not Path(exe).exists():
        pytest.skip(f"no isotrack binary at {exe} (build with cargo build --release)")
    return exe


# The child saves a run of ROWS trace rows into DIR. First it times the save of a run of
# 16 384 rows, the rows `write_run` writes between two checks for Ctrl-C (one check
# interval, on this machine under its present load); then it says `ready INTERVAL` and saves
# the big run, which takes hundreds of intervals.
SAVER = textwrap.dedent(
    """
    import os, signal, sys, time
    import isotrack
    rows, d, calib = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    sc = isotrack.Scenario.default().set("output.record_rate_hz", 100.0)
    small = sc.set("sim.duration_s", 163.84).run()
    t = time.monotonic()
    small.save(calib)
    interval = time.monotonic() - t
    big = sc.set("sim.duration_s", rows / 100.0).run()
    assert len(big.trace["t_s"]) == rows + 1
    # Where the save was when Ctrl-C was answered: whether its temporary trace
    # (`.trace.csv.PID.tmp`, made once the columns are copied) existed yet.
    begun = []
    def on_int(sig, frame):
        begun.append(os.path.isdir(d) and any(n.startswith(".trace.csv.") for n in os.listdir(d)))
        raise KeyboardInterrupt
    signal.signal(signal.SIGINT, on_int)
    # "ready" is printed inside the try, so a signal that arrives before the save has begun
    # is still answered by the except below (the parent sends it as soon as it reads "ready").
    t0 = time.monotonic()
    try:
        print("ready", interval, os.getpid(), flush=True)
        big.save(d)
        print("finished", time.monotonic() - t0, flush=True)
    except KeyboardInterrupt:
        print("interrupted", time.monotonic() - t0, "writing" if begun[0] else "copying", flush=True)
    """
)


def saver(tmp_path, rows, d):
    p = subprocess.Popen(
        [sys.executable, "-c", SAVER, str(rows), str(d), str(tmp_path / "calib")],
        stdout=subprocess.PIPE,
        text=True,
    )
    word, interval, pid = p.stdout.readline().split()
    assert word == "ready"
    return p, float(interval)


@pytest.mark.parametrize("existing", [False, True])
def test_ctrl_c_during_a_large_save_raises_at_once_and_leaves_no_half_written_run(tmp_path, existing):
    """A SIGINT sent as a 6e6-row save starts raises KeyboardInterrupt while the save still
    copies the run's columns (a few hundred milliseconds of copying before the first row is
    written: the copy once held the signal until it was done, answered only as the first row
    was written) and within 40 check intervals (the save itself takes about 370). No
    half-written run is left: a new directory is removed, an existing run directory keeps its
    earlier run byte for byte (the trace is written into a temporary file beside it), and
    neither a temporary file nor the lock file stays."""
    d = tmp_path / "run"
    before = {}
    if existing:
        isotrack.Scenario.default().set("sim.duration_s", 5.0).run().save(str(d))
        before = {f: (d / f).read_bytes() for f in RUN_FILES}
    p, interval = saver(tmp_path, 6_000_000, d)
    try:
        t_sig = time.monotonic()
        p.send_signal(signal.SIGINT)
        line = p.stdout.readline().split()
        answered = time.monotonic() - t_sig
        assert p.wait(timeout=300) == 0
    finally:
        p.kill()
    assert line and line[0] == "interrupted", line
    assert line[2] == "copying", line
    assert answered < 40 * interval + 0.05, (answered, interval)
    if existing:
        assert sorted(os.listdir(d)) == RUN_FILES
        assert {f: (d / f).read_bytes() for f in RUN_FILES} == before
    else:
        assert not d.exists(), os.listdir(d)


def wait_for_lock(d, holder, timeout=120.0):
    """The holder record in `d/.isotrack.lock` once it names `holder` (`run pid N`)."""
    lock = Path(d) / ".isotrack.lock"
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        try:
            text = lock.read_text()
        except OSError:
            text = ""
        if text.startswith(holder):
            return text
        time.sleep(0.01)
    raise AssertionError(f"no {holder} lock in {d}")


def test_save_refuses_a_directory_the_cli_is_writing(tmp_path):
    """att30c-6: while `isotrack run --out D` holds D's lock, `Run.save(D)` raises an OSError
    naming the holder (the CLI's 73) and writes nothing there; once the CLI is done, the save
    goes through."""
    d = tmp_path / "D"
    run = isotrack.Scenario.default().set("sim.duration_s", 5.0).run()
    p = subprocess.Popen(
        [cli(), "run", "--out", str(d), "--quiet", "--set", "sim.duration_s=600000.0", "--set", "output.record_rate_hz=0.0"],
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        holder = wait_for_lock(d, "run pid")
        assert f"run pid {p.pid}" in holder, holder
        with pytest.raises(OSError) as e:
            run.save(str(d))
        assert f"run pid {p.pid}" in str(e.value), str(e.value)
        assert ".isotrack.lock" in str(e.value), str(e.value)
        # In Python's words, not the command line's (`--out`): ver30b's brief item 3.
        assert "--out" not in str(e.value) and "save into another directory" in str(e.value), str(e.value)
        assert not (d / "summary.json").exists()
    finally:
        p.send_signal(signal.SIGTERM)
        p.wait(timeout=120)
    run.save(str(d))
    assert sorted(os.listdir(d)) == RUN_FILES


def test_the_cli_refuses_a_directory_a_save_is_writing(tmp_path):
    """att30c-6, the other way: while `Run.save(F)` of a 4e6-row run writes F (holding its
    lock), `isotrack run --out F` exits 73 naming `Run.save` and its pid, and F keeps nothing of
    the CLI's run (its summary would have replaced the saved run's without a word)."""
    f = tmp_path / "F"
    p, _ = saver(tmp_path, 4_000_000, f)
    try:
        holder = wait_for_lock(f, "Run.save pid")
        o = subprocess.run([cli(), "run", "--out", str(f), "--quiet", "--set", "sim.duration_s=1.0"], capture_output=True, text=True)
        assert o.returncode == 73, o.stderr
        assert f"Run.save pid {p.pid}" in o.stderr, o.stderr
        assert holder.split(" on ")[0] == f"Run.save pid {p.pid}", holder
        assert not (f / "summary.json").exists()
        p.send_signal(signal.SIGINT)
        assert p.stdout.readline().split()[0] == "interrupted"
        assert p.wait(timeout=300) == 0
    finally:
        p.kill()
    assert not f.exists(), os.listdir(f)


def test_plot_never_replaces_a_users_own_figure(tmp_path):
    """att40-25: `isotrack.plot` drew into a staging folder, so the command's check of the
    figures it replaces (att38-9: only isotrack's marked figures) looked into an empty folder,
    and the user's own trajectory.png and animation.gif were then moved over. Now refused
    (OSError naming the file), the user's files byte for byte as they were, in a run directory
    and in a folder given as `out`; isotrack's own figures are still redrawn."""
    run = isotrack.Scenario.default().set("sim.duration_s", 5.0).run()
    d = tmp_path / "run"
    run.save(d)
    mine = b"MY OWN PICTURE, three weeks of work"
    (d / "trajectory.png").write_bytes(mine)
    with pytest.raises(OSError, match="trajectory.png is not a figure isotrack wrote"):
        isotrack.plot(str(d))
    assert (d / "trajectory.png").read_bytes() == mine
    assert not (d / "timeseries.png").exists()
    assert [p.name for p in d.iterdir() if p.name.startswith(".isotrack-partial")] == []

    out = tmp_path / "figs"
    out.mkdir()
    (out / "animation.gif").write_bytes(mine)
    with pytest.raises(OSError, match="animation.gif is not a figure isotrack wrote"):
        isotrack.plot(str(d), out=str(out), animate=True)
    assert (out / "animation.gif").read_bytes() == mine

    (d / "trajectory.png").unlink()
    isotrack.plot(str(d))
    first = (d / "trajectory.png").read_bytes()
    assert first.startswith(b"\x89PNG")
    isotrack.plot(str(d))
    assert (d / "trajectory.png").read_bytes().startswith(b"\x89PNG")


def test_plot_waits_for_a_run_writing_the_directory(tmp_path):
    """att40-27: `isotrack.plot` into a run directory takes the lock `isotrack plot` takes, so
    it is refused (OSError naming the holder) while `run --out` writes there."""
    d = tmp_path / "run"
    isotrack.Scenario.default().set("sim.duration_s", 5.0).run().save(d)
    scenario = tmp_path / "long.toml"
    scenario.write_text((ROOT / "scenarios" / "paper-fig2b-circular.toml").read_text())
    p = subprocess.Popen(
        [cli(), "run", str(scenario), "--out", str(d), "--quiet", "--set", "sim.duration_s=3000000"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 30.0
        while not (d / ".isotrack.lock").exists():
            assert p.poll() is None, p.stderr.read()
            assert time.monotonic() < deadline
            time.sleep(0.02)
        with pytest.raises(OSError, match="writing this directory"):
            isotrack.plot(str(d))
    finally:
        p.kill()
        p.wait()


def test_save_never_replaces_a_users_summary_or_trace(tmp_path):
    """att39-1: `Run.save(P)` into a folder holding the user's own summary.json (not an
    isotrack run's) and trace.csv replaced both without a word. It raises an OSError naming the
    file (the CLI's exit 73) and every file is as it was; a folder holding an earlier save is
    replaced as before."""
    run = isotrack.Scenario.default().set("sim.duration_s", 5.0).run()
    cases = [
        ({"summary.json": '{"my": "results"}\n', "trace.csv": "t,my,data\n"}, "summary.json",
         "is not an isotrack run's summary"),
        ({"trace.csv": "t,my,data\n"}, "trace.csv", "no summary.json beside it"),
    ]
    for i, (files, named, why) in enumerate(cases):
        p = tmp_path / f"P{i}"
        p.mkdir()
        for name, text in files.items():
            (p / name).write_text(text)
        with pytest.raises(OSError) as e:
            run.save(str(p))
        message = str(e.value)
        assert str(p / named) in message and why in message, message
        assert "save into another directory" in message, message
        assert sorted(os.listdir(p)) == sorted(files)
        for name, text in files.items():
            assert (p / name).read_text() == text
    earlier = tmp_path / "earlier"
    run.save(str(earlier))
    run.save(str(earlier))
    assert sorted(os.listdir(earlier)) == RUN_FILES


def test_plot_of_a_sweep_draws_into_the_sweep(tmp_path):
    """att41-16: `isotrack.plot(SWEEP)` took the sweep directory's lock, then the command took
    it again for its input and refused its own process: every sweep plot into the sweep
    failed. It draws the sweep figure there."""
    sw = tmp_path / "sw.toml"
    sw.write_text(
        f'scenario = "{ROOT / "scenarios" / "paper-fig2b-circular.toml"}"\n'
        "[base]\nsim.duration_s = 5.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"
    )
    out = tmp_path / "swd"
    subprocess.run([cli(), "sweep", str(sw), "--out", str(out)], check=True, capture_output=True)
    isotrack.plot(str(out))
    drawn = [p.name for p in out.iterdir() if p.name.startswith("sweep_") and p.suffix == ".png"]
    assert drawn, sorted(p.name for p in out.iterdir())
    assert not (out / ".isotrack.lock").exists()


def test_plot_of_a_sweep_never_replaces_a_users_file_named_as_its_figure(tmp_path):
    """att41-10 (Python addendum): `isotrack.plot(SWEEP, out=...)` moved its figure over the
    user's own file of that name (`sweep_METRIC_vs_X.png`, no isotrack mark). Refused
    (OSError naming the file), the file byte for byte as it was, into the sweep and into
    `out`; isotrack's own figure is still redrawn."""
    sw = tmp_path / "sw.toml"
    sw.write_text(
        f'scenario = "{ROOT / "scenarios" / "paper-fig2b-circular.toml"}"\n'
        "[base]\nsim.duration_s = 5.0\n[grid]\ncontroller.kp = [5.0, 10.0]\n"
    )
    swd = tmp_path / "swd"
    subprocess.run([cli(), "sweep", str(sw), "--out", str(swd)], check=True, capture_output=True)
    name = "sweep_steady_state_max_abs_error_vs_controller_kp.png"
    mine = b"MY OWN SWEEP PLOT"
    out = tmp_path / "so3"
    out.mkdir()
    for d, kwargs in [(swd, {}), (out, {"out": str(out)})]:
        (d / name).write_bytes(mine)
        with pytest.raises(OSError, match=f"{name} is not a figure isotrack wrote"):
            isotrack.plot(str(swd), **kwargs)
        assert (d / name).read_bytes() == mine
        assert [p.name for p in d.iterdir() if p.name.startswith(".isotrack-partial")] == []
        (d / name).unlink()
    isotrack.plot(str(swd), out=str(out))
    isotrack.plot(str(swd), out=str(out))
    assert (out / name).read_bytes().startswith(b"\x89PNG")
