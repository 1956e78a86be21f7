"""Verify any family's C against its integer model: on the host (gcc with UBSan and ASan, the
portable path) and on the simulated chips (simavr, gpsim; the fast path, and on request the
portable path too). Every result carries the hash of the C it ran."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.files.c_hash import dir_hash, files_hash
from nnik.errors import NnikError
from nnik.implementations.base import Implementation

HOST_RANDOM = 20_000


def _write(impl: Implementation, c_dir: Path, write: bool = True) -> str | None:
    """Write the implementation's C into c_dir (or, with ``write=False``, leave the files there
    as they are); returns the hash of the C that will run."""
    from nnik.files.atomic_write import Staged

    if not write:
        return dir_hash(c_dir, impl.problem.name)
    staged = Staged(c_dir)  # whole files or the old ones: a full disk never leaves half a C file
    staged.add(impl.render_c())
    staged.commit()
    return files_hash(impl.render_c())


def host_vectors(impl: Implementation, n_random: int = HOST_RANDOM, seed: int = 0) -> np.ndarray:
    """Random in-domain points, the check set's first rows, every corner and out-of-domain points
    (including the int32 extremes)."""
    p = impl.problem
    lo, hi = p.lo, p.hi
    rng = np.random.default_rng(seed)
    span = hi - lo
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]], dtype=np.int64)
    outside = np.concatenate([
        corners + np.array([[-1, -1], [-1, 1], [1, -1], [1, 1]]),
        rng.integers(lo - span, hi + span + 1, (500, 2)),
        np.array([[-(2**31), -(2**31)], [2**31 - 1, 2**31 - 1], [-(2**31), 2**31 - 1]], dtype=np.int64)])
    return np.concatenate([rng.integers(lo, hi + 1, (n_random, 2)), p.check[0][:2000], corners, outside])


def target_vectors(impl: Implementation, n: int = 200, seed: int = 1) -> np.ndarray:
    """A few hundred vectors for a simulator: random in-domain points (their mean cycles are the
    figure of merit), then corners and out-of-domain points."""
    p = impl.problem
    lo, hi = p.lo, p.hi
    rng = np.random.default_rng(seed)
    corners = np.array([[lo[0], lo[1]], [lo[0], hi[1]], [hi[0], lo[1]], [hi[0], hi[1]]], dtype=np.int64)
    span = hi - lo
    outside = np.array([[lo[0] - 1, lo[1]], [hi[0] + 1, hi[1]], [lo[0], hi[1] + span[1]],
                        [-(2**31), 2**31 - 1], [2**31 - 1, -(2**31)]], dtype=np.int64)
    return np.concatenate([rng.integers(lo, hi + 1, (n, 2)), corners, outside])


def verify_host(impl: Implementation, c_dir: Path, vectors: np.ndarray | None = None, write: bool = True) -> dict:
    """Compile NAME.c (portable path) with sanitizers, run it, compare with the integer model
    (``write=False``: the NAME.{c,h} already in c_dir, as they are)."""
    from nnik.targets.host import run_host_driver

    c_hash = _write(impl, c_dir, write)
    vec = host_vectors(impl) if vectors is None else vectors
    c = run_host_driver(c_dir, impl.problem.name, vec)
    r = impl.run(vec)
    bad = np.any(c["out"] != r.out, axis=1) | (c["flags"] != r.flags)
    return {"points": int(len(vec)), "mismatches": int(bad.sum()), "bit_exact": bool(not bad.any()),
            "model_hash": impl.source_hash(), "c_hash": c_hash}


def verify_on_target(impl: Implementation, target: str, c_dir: Path, workdir: Path, portable: bool = False,
                     vectors: np.ndarray | None = None, n_inside: int = 200, write: bool = True) -> dict:
    """Run NAME.c on the simulator; cycles are the mean over the random in-domain vectors."""
    from nnik.targets import TargetError, available, run_on_target

    ok, reason = available(target)
    if not ok:
        return {"not_run": reason, "model_hash": impl.source_hash()}
    c_hash = _write(impl, c_dir, write)
    vec = target_vectors(impl, n_inside) if vectors is None else vectors
    name = impl.problem.name
    try:
        res = run_on_target(target=target, sources=[c_dir / f"{name}.c"], include_dirs=[c_dir], name=name,
                            vectors=vec, opt="-Os", workdir=Path(workdir).resolve(),
                            extra_cflags=["-DNNIK_PORTABLE"] if portable else [])
    except TargetError as exc:
        raise NnikError(f"{target}: {impl.family}: {exc}") from None
    r = impl.run(vec)
    bad = np.any(res["outputs"] != r.out, axis=1) | (res["flags"] != r.flags)
    inside = np.all((vec >= impl.problem.lo) & (vec <= impl.problem.hi), axis=1)
    cyc = np.asarray(res["cycles"], dtype=np.float64)
    return {"cycles": float(cyc[inside].mean()), "cycles_max": int(cyc.max()),
            "flash_bytes": int(res["model_flash_bytes"]), "ram_bytes": int(res["model_ram_bytes"]),
            "points": int(len(vec)), "mismatches": int(bad.sum()), "bit_exact": bool(not bad.any()),
            "compiler": res["compiler"], "path": "portable" if portable else "fast",
            "model_hash": impl.source_hash(), "c_hash": c_hash}
