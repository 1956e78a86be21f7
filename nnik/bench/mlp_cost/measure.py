"""Measurements on the simulators: the shift microbenchmark and the calibration networks."""

from __future__ import annotations

import functools
import hashlib
import os
import pickle
from pathlib import Path

import numpy as np

from nnik.errors import NnikError
from nnik.implementations.mlp.cost.coverage import measurable
from nnik.implementations.mlp.cost.kernels import kernel_key, render_c, write_c
from nnik.implementations.mlp.cost.calibrations import BUILTIN_PROFILES
from nnik.implementations.mlp.cost.shifts import MAX_SHIFT, SHIFT_GROUPS, SHIFTS, shift_bench_c
from nnik.implementations.mlp.cost.synthetic import (PIC18_COVERAGE_SPECS, CalSpec, calibration_specs, in_domain_vectors,
                                                     synthetic_model)


@functools.cache
def portable_shift_style() -> str:
    """How the portable template writes a shift by a constant: "chain8" (>> 8 >> 8 >> 1, as
    SDCC-safe C) or "plain" (>> 17); read from a rendered probe network."""
    im = synthetic_model(CalSpec("galvo", (3,), seed=1, gain=0.3))
    L = im.hidden[0]
    text = render_c(im)[f"{im.name}.c"]
    return "chain8" if L.sh > 8 and f"L) >> 8 >> {min(L.sh - 8, 8)}" in text else "plain"


def run_profile(profile: str, csrc: Path, name: str, vec: np.ndarray, n_out: int, workdir: Path) -> dict:
    from nnik.targets import TargetError, run_on_target

    p = BUILTIN_PROFILES[profile]
    try:
        return run_on_target(target=p["target"], sources=[csrc], include_dirs=[csrc.parent], name=name,
                             vectors=vec, opt=p["opt"] or "-Os", workdir=workdir, n_out=n_out, progress=False)
    except TargetError as exc:
        raise NnikError(f"{profile}: {exc}") from None


def _pic18_function_sizes(workdir: Path, prefix: str) -> dict[str, int]:
    """Code bytes per function of the model object, from the gplink map of the size build."""
    maps = list(workdir.rglob("size_model/prog.map"))
    sizes: dict[str, int] = {}
    if not maps:
        return sizes
    for line in maps[0].read_text(errors="replace").splitlines():
        parts = line.split()
        if len(parts) == 5 and parts[1] == "code" and parts[3] == "program" and f"__{prefix}_" in parts[0]:
            fn = parts[0].split("__", 1)[1]
            sizes[fn] = int(parts[4], 16)
    return sizes


def _avr_function_sizes(workdir: Path, prefix: str) -> dict[str, int]:
    from nnik.targets.toolchain import find_tool, run

    objs = list(workdir.rglob("model0_*.o"))
    sizes: dict[str, int] = {}
    if not objs:
        return sizes
    res = run([find_tool("avr-nm"), "-S", "--size-sort", objs[0]], "avr-nm", cwd=workdir)
    for line in res.stdout.splitlines():
        parts = line.split()
        if len(parts) == 4 and parts[3].startswith(prefix + "_"):
            sizes[parts[3]] = int(parts[1], 16)
    return sizes


def measure_shift_tables(profile: str, workdir: Path) -> dict:
    """Cycles and code bytes of (x + 2^(n-1)) >> n, its int16-narrowed form, x >> n and x * 2^n for
    n = 1..31 (index 0 = no shift = 0), net of the dispatch overhead; the same with the shift
    written as a chain of shifts by at most 8.  Two programs (a PIC18's flash holds one group)."""
    shifts = SHIFTS
    tables: dict = {"cycles": {}, "bytes": {}}
    target = BUILTIN_PROFILES[profile]["target"]
    for gi, kinds in enumerate(SHIFT_GROUPS):
        name, text = shift_bench_c(gi)
        nk = len(kinds)
        d = workdir / f"shifts{gi}"
        d.mkdir(parents=True, exist_ok=True)
        (d / f"{name}.c").write_text(text)
        rows = [(0, 0x12345)] + [(1 + nk * i + k, x) for i in range(len(shifts)) for k in range(nk)
                                 for x in (0x12345678, -0x0ABCDE)]
        r = run_profile(profile, d / f"{name}.c", name, np.array(rows, dtype=np.int64), 2, d / "w")
        cyc = r["cycles"].astype(float)
        ident = cyc[0]
        sizes = (_avr_function_sizes if target == "avr" else _pic18_function_sizes)(d / "w", name)
        ident_b = sizes.get(f"{name}_id")
        for k, kind in enumerate(kinds):
            tables["cycles"][kind] = [0.0] * (MAX_SHIFT + 1)
            tables["bytes"][kind] = [0.0] * (MAX_SHIFT + 1)
            for i, n in enumerate(shifts):
                j = 1 + 2 * (nk * i + k)
                tables["cycles"][kind][n] = float(np.mean(cyc[j:j + 2]) - ident)
                b = sizes.get(f"{name}_{kind}{n}")
                if b is not None and ident_b is not None:
                    tables["bytes"][kind][n] = float(b - ident_b)
        tables.setdefault("dispatch_cycles", float(ident))
    tables["style"] = portable_shift_style()
    return tables


def measurement_key(profile: str, csrc: Path, vec: np.ndarray) -> str:
    """What a measurement depends on: the profile, the model's C (with the runtime headers and
    harnesses, which the kernel's reference hash covers) and the input vectors."""
    from nnik.implementations.mlp.cost.validity import reference_c_hash

    h = hashlib.sha256()
    for part in (profile.encode(), reference_c_hash("fast").encode(), reference_c_hash(None).encode(),
                 csrc.read_bytes(), np.ascontiguousarray(vec, dtype=np.int64).tobytes()):
        h.update(part + b"\0")
    return h.hexdigest()[:24]


def measure_kernel(prof: str, kern: str | None, wd: Path, say, jobs: int | None = None) -> list[dict]:
    """Build and run every calibration network with one kernel: [{label, im, vec, cycles, flash, ram}].
    The networks are independent: `jobs` of them run at once (default: the CPU count, at most 4)."""
    from concurrent.futures import ThreadPoolExecutor

    kkey = kernel_key(kern)
    target = BUILTIN_PROFILES[prof]["target"]
    specs = calibration_specs(kern, target=target) + (list(PIC18_COVERAGE_SPECS) if kern == "fast" and target == "pic18" else [])
    jobs = jobs or max(1, min(4, os.cpu_count() or 1))

    def one(i: int, sp: CalSpec):
        im = synthetic_model(sp, kernel=kern)
        if kern == "fast" and not measurable(sp, im, target):
            # SDCC needs minutes to compile the unrolled C of a larger fast network (10 min for 2-17-3-2)
            say(f"[{prof}/{kkey}] {i + 1}/{len(specs)} {sp.label}: skipped (SDCC compile time of the fast C path)")
            return None
        d = wd / kkey / f"m{i:02d}"
        csrc = write_c(im, d / "c", kernel=kern)
        vec = in_domain_vectors(im, sp.n_vec, seed=sp.seed + 7)
        cached = wd / kkey / "cache" / f"{measurement_key(prof, csrc, vec)}.pkl"
        if cached.is_file():  # the same C and vectors measured by an earlier run (simulators are deterministic)
            m = pickle.loads(cached.read_bytes())
            say(f"[{prof}/{kkey}] {i + 1}/{len(specs)} {sp.label}: {np.mean(m['cycles']):.0f} cycles (measured before)")
            return {**m, "label": sp.label, "im": im, "vec": vec}
        r = run_profile(prof, csrc, im.name, vec, im.shape[-1], d / "w")
        frame = _avr_frame_size(prof, csrc, im.name) if target == "avr" else None
        say(f"[{prof}/{kkey}] {i + 1}/{len(specs)} {sp.label}: {r['cycles_mean']:.0f} cycles, "
            f"{r['model_flash_bytes']} B flash")
        m = {"cycles": r["cycles"].astype(float), "frame": frame, "target": target,
             "flash": float(r["model_flash_bytes"]), "ram": float(r["model_ram_bytes"]),
             "compiler": r["compiler"], "flags": r["compiler_flags"]}
        cached.parent.mkdir(parents=True, exist_ok=True)
        cached.write_bytes(pickle.dumps(m))
        return {**m, "label": sp.label, "im": im, "vec": vec}

    # the random draws happen in synthetic_model with per-spec seeds: the order of completion is irrelevant
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(lambda a: one(*a), enumerate(specs)))
    return [m for m in results if m is not None]


def _avr_frame_size(prof: str, csrc: Path, name: str) -> int | None:
    """Stack frame bytes of NAME_ik as avr-gcc reports them in the assembly (compile only)."""
    import re

    from nnik.targets.avr import compile_flags
    from nnik.targets.toolchain import find_tool, run

    res = run([find_tool("avr-gcc"), *compile_flags(BUILTIN_PROFILES[prof]["opt"]), f"-I{csrc.parent}", "-S",
               "-o", "-", csrc], "avr-gcc -S", cwd=csrc.parent)
    m = re.search(rf"^{re.escape(name)}_ik:.*?frame size = (\d+)", res.stdout, re.DOTALL | re.MULTILINE)
    return int(m.group(1)) if m else None
