"""The golden manifest's python/ lines (issue 31): the Python default run, saved with Run.save and
its trace arrays hashed, against tests/golden/MANIFEST.sha256 (its header says how each output is
hashed). ISOTRACK_GOLDEN_UPDATE=1 rewrites these lines instead (scripts/golden.sh --update)."""

import hashlib
import os
import tempfile
from pathlib import Path

import numpy as np

import isotrack

ROOT = Path(__file__).resolve().parents[2]
MANIFEST = ROOT / "tests" / "golden" / "MANIFEST.sha256"
PREFIX = "python/"
#: trace.csv's columns, in its order (the Dubins robot: no telemetry columns).
COLUMNS = ["t_s", "x_m", "y_m", "heading_rad", "s", "error", "omega_radps", "s_measured"]
CANONICAL_NAN = np.uint64(0x7FF8000000000000)


def normalised(data: bytes, out: str) -> bytes:
    """The manifest header's normalisation: the output directory and the version string."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return data
    v = isotrack.__version__
    text = text.replace(out, "<OUT>").replace(str(ROOT), "<REPO>")
    text = text.replace(f'"isotrack_version": "{v}"', '"isotrack_version": "<VERSION>"')
    text = text.replace(f"isotrack {v}", "isotrack <VERSION>")
    return text.encode("utf-8")


def trace_arrays_digest(trace) -> str:
    """Each column in trace.csv's order: its name, a newline, its values as little-endian float64
    (NaN as 0x7ff8000000000000); SHA-256 of the concatenation."""
    h = hashlib.sha256()
    assert list(trace) == COLUMNS, list(trace)
    for name in COLUMNS:
        bits = np.ascontiguousarray(trace[name], dtype="<f8").view("<u8").copy()
        bits[np.isnan(trace[name])] = CANONICAL_NAN
        h.update(name.encode() + b"\n")
        h.update(bits.astype("<u8").tobytes())
    return h.hexdigest()


def python_hashes() -> dict:
    run = isotrack.Scenario.default().run()
    got = {}
    with tempfile.TemporaryDirectory() as d:
        d = os.path.realpath(d)
        run.save(os.path.join(d, "default"))
        for f in sorted(Path(d, "default").rglob("*")):
            if f.is_file():
                rel = f.relative_to(d).as_posix()
                got[PREFIX + rel] = hashlib.sha256(normalised(f.read_bytes(), d)).hexdigest()
    got[PREFIX + "default/trace-arrays.f64le"] = trace_arrays_digest(run.trace)
    return got


def read_manifest():
    header, entries = [], {}
    for line in MANIFEST.read_text().splitlines():
        if line.startswith("#") or not line.strip():
            header.append(line)
        else:
            digest, name = line.split("  ", 1)
            entries[name] = digest
    return header, entries


def test_python_default_run_matches_the_golden_manifest():
    got = python_hashes()
    header, entries = read_manifest()
    if os.environ.get("ISOTRACK_GOLDEN_UPDATE") == "1":
        kept = {n: h for n, h in entries.items() if not n.startswith(PREFIX)}
        kept.update(got)
        lines = header + [f"{kept[n]}  {n}" for n in sorted(kept)]
        MANIFEST.write_text("\n".join(lines) + "\n")
        return
    want = {n: h for n, h in entries.items() if n.startswith(PREFIX)}
    problems = [f"  missing:  {n}" for n in sorted(set(want) - set(got))]
    problems += [f"  new:      {n}  {got[n]}" for n in sorted(set(got) - set(want))]
    problems += [
        f"  changed:  {n}  {want[n]} -> {got[n]}" for n in sorted(set(want) & set(got)) if want[n] != got[n]
    ]
    assert not problems, (
        f"{len(problems)} Python outputs differ from {MANIFEST.relative_to(ROOT)}:\n"
        + "\n".join(problems)
        + "\nIf every difference is intended, regenerate with `scripts/golden.sh --update` and "
        "list every changed output in the commit message, with the reason."
    )


def test_python_default_run_files_are_the_cli_default_run_files():
    """Run.save writes the bytes `isotrack run --out` writes: the manifest's python/default/ files
    have the hashes of its run/default/ files."""
    _, entries = read_manifest()
    for f in ("trace.csv", "summary.json", "scenario.toml"):
        assert entries[PREFIX + "default/" + f] == entries["run/default/" + f], f
