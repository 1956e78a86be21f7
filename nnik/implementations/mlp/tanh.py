"""tanh replacements for fixed-point MLPs on 8-bit MCUs.

Integer contract (the generated network code depends on it)
-----------------------------------------------------------
* input  ``v``: int16 in Q3.12, x = v / 4096, covering [-8, 8);
* output ``r``: int16 in Q15,  y = r / 32768, always in [-32767, 32767];
* odd by construction: the C evaluates |v| (as uint16, so v = -32768 is safe) and restores
  the sign, hence ``tanh_int(-v) == -tanh_int(v)`` for every v > -32768;
* only int16/int32 arithmetic (16x16 -> 32 products at most), no int64, no float, no left
  shift of a negative value.  Right shifts of negative int32 values (polynomial forms only)
  are arithmetic, as on gcc, avr-gcc and SDCC; numpy's ``>>`` on int64 emulates that.

:func:`tanh_int` is the bit-exact Python oracle of the C that :func:`render_tanh_c`
emits; the tests compare the two on all 65536 inputs.

Forms
-----
``poly``  piecewise polynomials on |x|, one local variable per segment (t = x - x0, held
          as u = t * 2^(12+s) in int16), fixed-point Horner with per-step Q formats chosen
          from the magnitudes of the Horner partial sums.  Segments are either given by
          breakpoints (the paper, CBA 2012 eq. 10-14: [0,1], (1,2], (2,3], (3,5.3], then 1)
          or have power-of-two widths so that the segment index is ``|v| >> k``.
          Fitted by least squares (as the paper) or minimax (LP on the Q3.12 grid),
          optionally continuous at the breakpoints.
``lerp``  a table of Q15 nodes, indexed by the top bits of |v| and linearly interpolated
          with the low bits: one unsigned 16x8 or 16x16 -> 16 multiply, whose bound is
          checked at fit time (a region where it could wrap uses a 32-bit product).
          Regions of different power-of-two steps put fine steps where tanh curves most.
          Nodes start near-minimax and are then tuned, one LSB at a time, against the
          exact integer evaluation.  Monotone and 0 at 0 by construction.

The default (:data:`DEFAULT_VARIANT`, equal to ``choose_variant(2.0)``) is the cheapest
variant within 2 LSB, cost = (multiplies per call, table bytes): a 4-region table.

Errors are measured against tanh(v/4096) in float64.  Integer errors are in LSB of Q15
(1 LSB = 2^-15) over ALL 65536 int16 inputs.  Float errors, those of the unquantised
pieces, are absolute, over every Q3.12 point of [0, 8), that is a = 0..32767, step 2^-12.

Where things are: :mod:`~nnik.implementations.mlp.tanh_spec` (the constants and the variants'
specs), :mod:`~nnik.implementations.mlp.tanh_fit` (fitting them), :mod:`~nnik.implementations.mlp.tanh_eval`
(their integer evaluation); this module builds and serves them (:data:`VARIANTS`,
:func:`tanh_int`), measures them and renders their C.
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Iterator, Mapping, Sequence

import numpy as np

from nnik.emit.templating import RUNTIME as RUNTIME_DIR
from nnik.errors import NnikError
from nnik.implementations.mlp.tanh_eval import _all_inputs, _lerp_int_eval, _poly_int_eval, exact_q15
from nnik.implementations.mlp.tanh_fit import _build_lerp, _build_poly, _eval_pieces
from nnik.implementations.mlp.tanh_spec import (
    A_MAX, DEFAULT_VARIANT, PAPER_BREAKS, PAPER_PUBLISHED_COEFFS, PAPER_RMS, PolySpec, SPECS, Variant,
    Y_MAX)


# --------------------------------------------------------------------------------------
# registry
# --------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _build(name: str) -> Variant:
    for spec in SPECS:
        if spec.name == name:
            return _build_poly(spec) if isinstance(spec, PolySpec) else _build_lerp(spec)
    raise NnikError(f"unknown tanh variant {name!r}; known: {', '.join(s.name for s in SPECS)}")


@functools.lru_cache(maxsize=None)
def fit_variants() -> dict[str, Variant]:
    """All registered variants, fitted (deterministic; cached)."""
    return {spec.name: _build(spec.name) for spec in SPECS}


class _LazyVariants(Mapping):
    """``VARIANTS[name]`` fits on first use."""

    def __getitem__(self, name: str) -> Variant:
        return _build(name)

    def __iter__(self) -> Iterator[str]:
        return iter(s.name for s in SPECS)

    def __len__(self) -> int:
        return len(SPECS)


VARIANTS: Mapping[str, Variant] = _LazyVariants()


def get_variant(variant: str | Variant | None = None) -> Variant:
    if variant is None:
        return _build(DEFAULT_VARIANT)
    if isinstance(variant, Variant):
        return variant
    return _build(str(variant))


# --------------------------------------------------------------------------------------
# the integer oracle
# --------------------------------------------------------------------------------------


def tanh_int(v: np.ndarray | int, variant: str | Variant | None = None) -> np.ndarray:
    """Bit-exact model of the generated C: int16 Q3.12 in, int16 Q15 out (vectorised)."""
    var = get_variant(variant)
    v = np.asarray(v, dtype=np.int64)
    if v.size and (v.min() < -32768 or v.max() > 32767):
        raise NnikError("tanh_int: input outside int16")
    a = np.abs(v)  # 0..32768, as the C's uint16 |v|
    r = _poly_int_eval(var, a) if var.kind == "poly" else _lerp_int_eval(var, a)
    r = np.where(a >= var.sat_a, Y_MAX, r)
    if var.pin_zero:
        r = np.where(a == 0, 0, r)
    return np.where(v < 0, -r, r)


def tanh_float(x: np.ndarray, variant: str | Variant | None = None) -> np.ndarray:
    """The unquantised pieces (float64) of a variant."""
    return _eval_pieces(get_variant(variant), x)


# --------------------------------------------------------------------------------------
# measurement
# --------------------------------------------------------------------------------------


@functools.lru_cache(maxsize=None)
def _sweep_cached(name: str) -> dict:
    return _sweep(_build(name))


def _sweep(var: Variant) -> dict:
    v = _all_inputs()
    e = tanh_int(v, var) - exact_q15(v)
    xa = np.arange(0, A_MAX, dtype=np.float64) / 4096.0
    ef = _eval_pieces(var, xa) - np.tanh(xa)
    r = tanh_int(np.arange(0, 32768), var)
    return dict(
        name=var.name,
        max_lsb=float(np.abs(e).max()),
        rms_lsb=float(np.sqrt(np.mean(e * e))),
        float_max_abs=float(np.abs(ef).max()),
        float_rms=float(np.sqrt(np.mean(ef * ef))),
        # the pieces alone, on [0, saturation): what the fitting method controls
        float_max_pieces=float(np.abs(ef[xa < var.sat_x]).max()),
        coeff_bytes=var.coeff_bytes,
        mults=var.mults,
        monotone=bool((np.diff(r) >= 0).all()),
    )


def sweep(variant: str | Variant | None = None) -> dict:
    """Errors of a variant: integer (LSB of Q15, all 65536 int16 inputs) and float
    (absolute, unquantised pieces on every Q3.12 point of [0, 8)), plus its flash bytes."""
    var = get_variant(variant)
    if _build_or_none(var.name) is var:
        return dict(_sweep_cached(var.name))
    return _sweep(var)


def _build_or_none(name: str) -> Variant | None:
    try:
        return _build(name)
    except NnikError:
        return None


def float_rms(variant: str | Variant, x_hi: float, n: int = 1_000_001) -> tuple[float, float]:
    """(RMS, max) absolute error of the float pieces on a uniform grid of n points over [0, x_hi]."""
    x = np.linspace(0.0, x_hi, n)
    e = _eval_pieces(get_variant(variant), x) - np.tanh(x)
    return float(np.sqrt(np.mean(e * e))), float(np.abs(e).max())


def published_paper_errors(x_hi: float = 5.3, n: int = 1_000_001) -> tuple[float, float]:
    """(RMS, max) of the coefficients as printed in the paper, same grid as :func:`float_rms`."""
    x = np.linspace(0.0, x_hi, n)
    y = np.ones_like(x)
    for j, c in enumerate(PAPER_PUBLISHED_COEFFS):
        lo, hi = PAPER_BREAKS[j], PAPER_BREAKS[j + 1]
        m = (x <= hi) & ((x > lo) | (j == 0))
        y[m] = np.polyval(c, x[m])
    e = y - np.tanh(x)
    return float(np.sqrt(np.mean(e * e))), float(np.abs(e).max())


def paper_report() -> dict:
    """The paper configuration next to the published RMS (1.7362e-5).

    Every figure is the error of float pieces against tanh on a uniform grid of
    1,000,001 points over [0, x_hi].  ``fit_*``: our least-squares fit (variant
    ``paper_lsq5``); ``printed_*``: the coefficients as printed in the paper.  The printed
    coefficients give 1.7363e-5 over [0, 6]: the published figure is reproduced by that
    range, and it is dominated by the rounding of the printed coefficients to 5 digits.
    """
    out = dict(published_rms=PAPER_RMS,
               grid="uniform, 1,000,001 points over [0, x_hi]; float pieces vs tanh")
    for tag, hi in (("0_5p3", 5.3), ("0_6", 6.0), ("0_8", 8.0)):
        r, m = float_rms("paper_lsq5", hi)
        out[f"fit_rms_{tag}"], out[f"fit_max_{tag}"] = r, m
        r, m = published_paper_errors(hi)
        out[f"printed_rms_{tag}"], out[f"printed_max_{tag}"] = r, m
    return out


def variants_table() -> list[dict]:
    """One row per variant for the CLI (``nnik tanh``)."""
    rows = []
    default = DEFAULT_VARIANT
    for name in VARIANTS:
        var = _build(name)
        s = sweep(var)
        rows.append(dict(
            name=name,
            form=f"{var.kind}/{var.method}",
            segments=var.nseg,
            degree=var.degree,
            saturation=var.sat_x,
            float_max=s["float_max_abs"],
            float_max_pieces=s["float_max_pieces"],
            float_rms=s["float_rms"],
            int_max_lsb=s["max_lsb"],
            int_rms_lsb=s["rms_lsb"],
            mults=var.mults,
            bytes=var.coeff_bytes,
            default=(name == default),
            description=var.description,
        ))
    return rows


def format_variants_table(rows: Sequence[dict] | None = None) -> str:
    """Plain-text rendering of :func:`variants_table`."""
    rows = variants_table() if rows is None else rows
    head = (f"{'variant':<17} {'form':<13} {'seg':>4} {'deg':>3} {'sat':>5} "
            f"{'fl max pcs':>10} {'float max':>10} {'float rms':>10} {'max LSB':>8} "
            f"{'rms LSB':>8} {'mul':>3} {'bytes':>5}")
    out = [head, "-" * len(head)]
    for r in rows:
        out.append(
            f"{r['name'] + (' *' if r['default'] else ''):<17} {r['form']:<13} {r['segments']:>4} "
            f"{r['degree']:>3} {r['saturation']:>5.3g} {r['float_max_pieces']:>10.3e} "
            f"{r['float_max']:>10.3e} "
            f"{r['float_rms']:>10.3e} {r['int_max_lsb']:>8.3f} {r['int_rms_lsb']:>8.3f} "
            f"{r['mults']:>3} {r['bytes']:>5}")
    out.append("* default.  Integer errors: LSB of Q15 over all 65536 int16 inputs.  Float: "
               "absolute error of the unquantised\npieces on every Q3.12 point of [0, 8) "
               "('fl max pcs': below the saturation point only).  mul: multiplies per call.")
    return "\n".join(out)


def choose_variant(max_lsb_budget: float = 2.0) -> Variant:
    """The cheapest variant whose integer max error is within the budget.
    Cost = (estimated multiplies per call, then flash bytes)."""
    ok = [(_build(n).cost, n) for n in VARIANTS if sweep(n)["max_lsb"] <= max_lsb_budget]
    if not ok:
        raise NnikError(f"no tanh variant within {max_lsb_budget} LSB")
    return _build(min(ok)[1])


# --------------------------------------------------------------------------------------
# C
# --------------------------------------------------------------------------------------


def _c_int_list(vals: Sequence[int], per_line: int = 10, indent: str = "    ") -> str:
    vals = [int(x) for x in vals]
    lines = []
    for i in range(0, len(vals), per_line):
        lines.append(indent + ", ".join(str(x) for x in vals[i:i + per_line]))
    return ",\n".join(lines)


def render_tanh_c(variant: str | Variant | None = None, prefix: str = "nnik") -> str:
    """C99 source of ``static int16_t {prefix}_tanh(int16_t v)`` and its flash tables."""
    from nnik.emit.templating import environment

    var = get_variant(variant)
    if not prefix.isidentifier():
        raise NnikError(f"C prefix {prefix!r} is not an identifier")
    env = environment()
    s = sweep(var)
    ctx = dict(prefix=prefix, v=var, stats=s, c_list=_c_int_list)
    if var.kind == "poly":
        ctx["coef_rows"] = [_c_int_list(row, per_line=16, indent="") for row in var.coef]
        ctx["sh_rows"] = [_c_int_list(row, per_line=16, indent="") for row in var.sh]
        # constant-shift Horner steps: "((p + 2^(sh-1)) >> sh)".  SDCC 4.2's pic16 port
        # miscompiles an int32 shift by exactly 15 (a stale carry enters bit 0; found by
        # running every variant in gpsim), so that one is written as >> 7 >> 8, which is
        # the same value for an arithmetic shift and which other compilers fold back
        ctx["terms"] = [
            (f"(((p + (int32_t){1 << (int(x) - 1)}) >> 7) >> 8)" if int(x) == 15
             else f"((p + (int32_t){1 << (int(x) - 1)}) >> {int(x)})")
            for x in var.sh[0]]
        ctx["q_uniform"] = bool((var.q == var.q[0]).all())
        if var.index_shift is not None:
            ctx["idx_mask"] = (1 << var.index_shift) - 1
    return env.get_template("tanh.c.j2").render(**ctx)


def run_c_model(variant: str | Variant | None = None, cc: str = "gcc",
                extra_flags: Sequence[str] = (), workdir: str | None = None) -> np.ndarray:
    """Compile the rendered C with a tiny driver on the host and return its 65536 outputs
    (inputs -32768..32767 in order)."""
    if shutil.which(cc) is None:
        raise NnikError(f"C compiler {cc!r} not found")
    src = render_tanh_c(variant, prefix="t")
    driver = (
        '#include <stdio.h>\n#include <stdint.h>\n#include "tanh_gen.c"\n'
        "int main(void)\n{\n    long i;\n"
        "    for (i = -32768L; i <= 32767L; i++) {\n"
        '        printf("%d\\n", (int)t_tanh((int16_t)i));\n    }\n    return 0;\n}\n'
    )
    with tempfile.TemporaryDirectory(dir=workdir) as d:
        Path(d, "tanh_gen.c").write_text(src)
        Path(d, "main.c").write_text(driver)
        exe = str(Path(d, "tanh_test"))
        cmd = [cc, "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror",
               *extra_flags, "-I", str(RUNTIME_DIR), "-o", exe, str(Path(d, "main.c"))]
        res = subprocess.run(cmd, capture_output=True, text=True)
        if res.returncode != 0:
            raise NnikError(f"C compile failed: {res.stderr.strip()}")
        env = dict(os.environ, UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1")
        run = subprocess.run([exe], capture_output=True, text=True, env=env)
        if run.returncode != 0 or run.stderr.strip():
            raise NnikError(f"C self-test failed: {run.stderr.strip()[:500]}")
        return np.array(run.stdout.split(), dtype=np.int64)


def c_mismatches(variant: str | Variant | None = None, cc: str = "gcc",
                 sanitize: bool = True) -> int:
    """Number of int16 inputs where the compiled C differs from :func:`tanh_int`."""
    flags = ["-fsanitize=undefined,address", "-fno-sanitize-recover=all"] if sanitize else []
    got = run_c_model(variant, cc=cc, extra_flags=flags)
    want = tanh_int(_all_inputs(), variant)
    if got.shape != want.shape:
        return int(want.size)
    return int(np.count_nonzero(got != want))
