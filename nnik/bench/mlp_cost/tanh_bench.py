"""The tanh replacements' C on the simulator, per input class (a calibration microbenchmark).

A tanh replacement inside the fast kernel's C path is a function whose cycles depend only on
the class of its input (segment or region, sign, saturation: nnik.implementations.mlp.cost.trace).
Fitted from whole networks, one coefficient per class is determined by the few calibration
networks whose tanh inputs reach that class, and a network whose inputs fall elsewhere inherits
their noise (issue 25: SDCC runs every minimax3_x11 segment in the same 1317 cycles, the fit
had spread them over +-110).  Measured here, each class costs what the chip says; the network fit
keeps these coefficients fixed (nnik.implementations.mlp.cost.sdcc_c.tanh_coefs)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from nnik.implementations.mlp.cost.trace import tanh_class_index, tanh_classes

_HEADER = ("#include <stdint.h>\n#define NNIK_TB_N_IN 2\n#define NNIK_TB_N_OUT 2\n"
           "int8_t nnik_tb_ik(const int32_t in_um[2], int32_t out[2]);\n")
# in_um[1] != 0: out = tanh(in_um[0]); 0: out = in_um[0] (the harness and call, subtracted)
_CALLER = ("\nint8_t nnik_tb_ik(const int32_t in_um[2], int32_t out[2])\n{\n"
           "    out[0] = in_um[1] ? nnik_tb_tanh((int16_t)in_um[0]) : (int16_t)in_um[0];\n"
           "    out[1] = 0;\n    return 0;\n}\n")
N_BASE = 8


def bench_inputs(seed: int = 1) -> np.ndarray:
    """int16 tanh inputs: random over the whole range, a dense sweep of the middle, the edges."""
    rng = np.random.default_rng(seed)
    return np.concatenate([rng.integers(-32768, 32768, 240), np.arange(-8000, 8001, 125),
                           [0, 1, -1, 32767, -32768, -32767]]).astype(np.int64)


def measure_tanh_classes(profile: str, variants: list[str], workdir: Path) -> dict[str, dict[str, float]]:
    """{variant: {class: mean cycles of one call}} for the classes the inputs reach."""
    from nnik.bench.mlp_cost.measure import run_profile
    from nnik.implementations.mlp.tanh import render_tanh_c
    from nnik.implementations.mlp.cost.kernels import write_c
    from nnik.implementations.mlp.cost.synthetic import CalSpec, synthetic_model

    flash_h = write_c(synthetic_model(CalSpec("galvo", (3,), seed=1, gain=0.3)), workdir / "probe").parent / "nnik_flash.h"
    T = bench_inputs()
    vec = np.stack([np.concatenate([T, T[:N_BASE]]), np.concatenate([np.ones(len(T)), np.zeros(N_BASE)])], 1)
    out: dict[str, dict[str, float]] = {}
    for V in variants:
        d = workdir / V
        d.mkdir(parents=True, exist_ok=True)
        (d / "nnik_flash.h").write_text(flash_h.read_text())
        (d / "nnik_tb.h").write_text(_HEADER)
        (d / "nnik_tb.c").write_text('#include <stdint.h>\n#include "nnik_flash.h"\n#include "nnik_tb.h"\n'
                                     + render_tanh_c(V, prefix="nnik_tb") + _CALLER)
        r = run_profile(profile, d / "nnik_tb.c", "nnik_tb", vec.astype(np.int64), 2, d / "w")
        cyc = r["cycles"].astype(float)
        net = cyc[:len(T)] - cyc[len(T):].mean()
        idx = tanh_class_index(V, T)
        out[V] = {name: round(float(net[idx == ci].mean()), 2) for ci, name in enumerate(tanh_classes(V))
                  if np.any(idx == ci)}
    return out
