"""Whether a calibration still describes the C the generator emits.

A calibration measured the C of its networks, not the Python that wrote it.  So its validity is
keyed to the C: ``reference_c_hash(kernel)`` hashes the C emitted today for a fixed set of
reference models (deterministic synthetic networks: a handful of shapes, every tanh variant,
residual and DAC outputs, int8 weights, looped and sparse fast layers) together with the runtime
headers the model's C includes, the simulator harnesses and the shift microbenchmark.  The calibration stores it per
kernel; an estimate is validated only while the stored and the recomputed hashes agree.  A
refactor that emits the same C keeps the calibration; any change in the emitted C needs
``python3 -m nnik.bench.mlp_cost calibrate`` again.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import re

from nnik.implementations.mlp.cost.calibrations import REPO_ROOT
from nnik.implementations.mlp.cost.kernels import render_c
from nnik.implementations.mlp.cost.shifts import SHIFT_GROUPS, shift_bench_c
from nnik.implementations.mlp.cost.synthetic import CalSpec, synthetic_model

# the source line the reference models' C carries: part of the hashed C, so it keeps the name the
# calibrations were measured under
REFERENCE_SOURCE = "nnik.estimate reference model"
# what a measured program contains besides the model: the simulator harnesses and the size stub
# (relative to the repository root), and the runtime headers the model's C includes
HARNESS_C = ("codegen/harness/avr", "codegen/harness/pic18", "codegen/harness/nnik_stub_model.c")
RUNTIME = "codegen/runtime"
_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.MULTILINE)


def _portable_specs() -> list[CalSpec]:
    from nnik.implementations.mlp import tanh as activations

    S = CalSpec
    per_variant = [S("galvo", (3,), tanh=v, seed=300, gain=3.0) for v in activations.VARIANTS]
    return per_variant + [
        S("galvo", (17, 3), seed=6),                          # two layers
        S("galvo_small", (3,), seed=19),                      # input stage without the pre-shift
        S("corexy", (3, 17), seed=23),                        # residual affine base
        S("dual", (18, 3), seed=26),                          # residual + DAC clamp
        S("galvo", (3, 17), weight_bits=8, seed=29),          # int8 weights
        S("galvo", (3, 24), seed=46),                         # a weight table of 128 bytes and more
        S("galvo", (17,), seed=15, out_scale=0.01),           # output shift signs
        S("galvo", (3,), seed=16, out_scale=60.0),
        S("galvo", (3, 3), seed=14, gain=0.7),                # tanh input clamp
    ]


def _fast_specs() -> list[CalSpec]:
    S = CalSpec
    own = [dataclasses.replace(s, tanh="") for s in (
        S("galvo", (3,), seed=60),
        S("galvo", (20, 3), seed=69, gain=0.6),
        S("galvo", (17, 17), seed=42),                        # a looped hidden-to-hidden layer
        S("corexy", (3, 3), seed=78),
        S("dual", (18, 3), seed=26),
        S("galvo", (3, 17), weight_bits=8, seed=29),
        S("galvo", (3, 20), seed=90, sparsity=0.5),           # zero weights skipped
        S("galvo_small", (3,), seed=19),
        S("galvo", (17,), seed=15, out_scale=0.01),
    )]
    return own + [S("galvo", (17,), tanh="lerp_mr4", seed=100, gain=3.0)]  # a portable tanh inside


def reference_specs(kernel: str | None) -> list[CalSpec]:
    """The reference models of a kernel (None: the generator's default, portable)."""
    return _fast_specs() if kernel == "fast" else _portable_specs()


def _harness_files() -> list[tuple[str, bytes]]:
    files = []
    for rel in HARNESS_C:
        base = REPO_ROOT / rel
        for p in sorted(base.rglob("*")) if base.is_dir() else [base]:
            if p.is_file() and p.suffix in (".c", ".h"):
                files.append((p.relative_to(REPO_ROOT).as_posix(), p.read_bytes()))
    for group in range(len(SHIFT_GROUPS)):
        name, text = shift_bench_c(group)
        files.append((f"{name}.c", text.encode()))
    return files


def _runtime_headers(texts: list[bytes]) -> list[tuple[str, bytes]]:
    """The runtime headers the given C includes, directly or through one another, by name."""
    found: dict[str, bytes] = {}
    todo = [t.decode(errors="replace") for t in texts]
    while todo:
        for name in _INCLUDE.findall(todo.pop()):
            p = REPO_ROOT / RUNTIME / name
            if name not in found and p.is_file():
                found[name] = p.read_bytes()
                todo.append(found[name].decode(errors="replace"))
    return [(f"{RUNTIME}/{n}", found[n]) for n in sorted(found)]


def reference_c(kernel: str | None) -> list[tuple[str, bytes]]:
    """(name, bytes) of every file the reference hash of a kernel covers, in a fixed order."""
    files = []
    for i, spec in enumerate(reference_specs(kernel)):
        im = synthetic_model(spec, kernel=kernel)
        for fname, text in sorted(render_c(im, REFERENCE_SOURCE, kernel=kernel).items()):
            files.append((f"{i:02d}:{spec.label}:{fname}", text.encode()))
    shared = _harness_files()
    return shared + _runtime_headers([d for _, d in files + shared]) + files


@functools.cache
def reference_c_hash(kernel: str | None = None) -> str:
    """Hash of the C emitted today for the reference models of a kernel, the runtime headers,
    the harnesses and the shift microbenchmark."""
    h = hashlib.sha256()
    for name, data in reference_c(kernel):
        h.update(name.encode() + b"\0" + str(len(data)).encode() + b"\0" + data)
    return h.hexdigest()[:16]


def stored_hash(cal: dict, kkey: str) -> str | None:
    """The reference hash a calibration file recorded for a kernel."""
    return (cal.get("kernels", {}).get(kkey) or {}).get("reference_c_hash")
