"""Same scenario and seed, same answer, whatever the machine's load: `nnik run` twice on one
scenario, once as the machine is and once with every core kept busy by spinning processes, then
the two output directories compared.

Compared byte for byte: the emitted C (`c/`), `pick.json`, `model.pt` and `data.npz`. Compared as
figures: `metrics.json` and the report's Markdown, with only the durations taken out (the keys in
TIMING_KEYS and the report's "training time" row), since how long a step took is the one thing
that load may change. The toolchains' own intermediates (map files, listings with a build date)
are not outputs and are not compared.

``python -m nnik.bench.reproducible SCENARIO.toml ...`` prints, per scenario, the two wall-clock
times, their ratio and every difference found (none is the pass); the CI test runs a small
scenario through the same function.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

BYTE_EXACT = ("pick.json", "model.pt", "data.npz")
TIMING_KEYS = {"train_seconds", "seconds", "trials_per_min"}
REPORT_TIMING = re.compile(r"^\| training time \(s\) \|.*$", re.M)


def spinners(n: int) -> list[subprocess.Popen]:
    """n processes that keep one core each busy until killed."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def run_once(toml: Path, out: Path, busy: int) -> float:
    """`nnik run TOML -o OUT` with `busy` spinning processes beside it; its wall-clock seconds."""
    procs = spinners(busy)
    t0 = time.perf_counter()
    try:
        r = subprocess.run([sys.executable, "-m", "nnik", "run", str(toml), "-o", str(out)],
                           capture_output=True, text=True)
    finally:
        for p in procs:
            p.kill()
            p.wait()
    if r.returncode != 0:
        raise RuntimeError(f"nnik run {toml} failed ({r.returncode}): {r.stderr.strip()[-2000:]}")
    return time.perf_counter() - t0


def _digest(p: Path) -> str:
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _untimed(v):
    if isinstance(v, dict):
        return {k: _untimed(x) for k, x in v.items() if k not in TIMING_KEYS}
    if isinstance(v, list):
        return [_untimed(x) for x in v]
    return v


def fingerprint(out: Path) -> dict[str, str]:
    """What must not depend on the load: {name: digest} of the C, the byte-exact files, the
    metrics without durations and the report's Markdown without its training time."""
    fp = {f"c/{p.relative_to(out / 'c')}": _digest(p) for p in sorted((out / "c").rglob("*")) if p.is_file()}
    for name in BYTE_EXACT:
        if (out / name).is_file():
            fp[name] = _digest(out / name)
    metrics = _untimed(json.loads((out / "metrics.json").read_text()))
    fp["metrics.json (without durations)"] = hashlib.sha256(json.dumps(metrics, sort_keys=True).encode()).hexdigest()
    md = out / "report" / "report.md"
    if md.is_file():
        fp["report.md (without the training time)"] = hashlib.sha256(
            REPORT_TIMING.sub("", md.read_text()).encode()).hexdigest()
    return fp


def compare(toml: Path, work: Path, busy: int | None = None) -> dict:
    """Run TOML idle, then under load, both into the same path (so that the paths that the report
    names are equal); returns {"seconds": [idle, loaded], "differences": [...], "compared": n}."""
    busy = (os.cpu_count() or 2) if busy is None else busy
    work = Path(work)
    out, first = work / "out", work / "idle"
    for d in (out, first):
        shutil.rmtree(d, ignore_errors=True)
    t_idle = run_once(toml, out, 0)
    out.rename(first)
    t_busy = run_once(toml, out, busy)
    a, b = fingerprint(first), fingerprint(out)
    diffs = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    return {"seconds": [t_idle, t_busy], "busy": busy, "differences": diffs, "compared": len(a)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m nnik.bench.reproducible", description=__doc__.split("\n\n")[0])
    ap.add_argument("scenarios", nargs="+", type=Path)
    ap.add_argument("--work", type=Path, default=Path("build/bench/reproducible"))
    args = ap.parse_args(argv)
    bad = 0
    for toml in args.scenarios:
        r = compare(toml, args.work / toml.stem)
        idle, loaded = r["seconds"]
        verdict = "identical" if not r["differences"] else "DIFFERENT: " + ", ".join(r["differences"])
        print(f"{toml.stem}: idle {idle:.0f} s, {r['busy']} cores busy {loaded:.0f} s "
              f"(x{loaded / idle:.2f}); {r['compared']} outputs compared: {verdict}")
        bad += bool(r["differences"])
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
