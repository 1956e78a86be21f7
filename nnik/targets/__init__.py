"""Build generated model C for 8-bit MCUs and run it on simulators.

    from nnik.targets import run_on_target
    res = run_on_target(target="avr", sources=[Path("gen/NAME.c")], include_dirs=[Path("gen")],
                        name="NAME", vectors=vec, opt="-Os", workdir=Path("build"))

Targets:
  "avr"   ATmega328P at 16 MHz, avr-gcc + simavr (cycles = CPU cycles)
  "pic18" PIC18F452 at 16 MHz, SDCC pic16 + gputils + gpsim (cycles = instruction
          cycles, Fosc/4)

The model must provide ``int8_t NAME_ik(const int32_t in_um[N_IN], int32_t out[N_OUT])``
(0 in domain, 1 if clamped).  The result dict has:
  outputs (N, n_out) int64, flags (N,) int64 (the return values), cycles (N,) int64,
  cycles_mean, cycles_max, flash_bytes, ram_bytes (whole harness program, one vector),
  model_flash_bytes, model_ram_bytes (difference to a stub of the same API),
  clock_hz, cycle_hz, us_mean, compiler (version), compiler_flags, target, simulator,
  calibration, workdir.
Failures raise TargetError (a RuntimeError) with a one-line message.
"""
from __future__ import annotations

from pathlib import Path
from typing import Dict, Optional, Sequence

from .toolchain import TargetError, available, prefix

__all__ = ["run_on_target", "available", "TargetError", "prefix", "TARGETS"]

TARGETS = ("avr", "pic18")


def run_on_target(target: str, sources: Sequence[Path], include_dirs: Sequence[Path] = (),
                  name: str = "model", vectors=None, opt: str = "-Os",
                  workdir: Optional[Path] = None, n_out: int = 2,
                  batch_size: Optional[int] = None, extra_cflags: Sequence[str] = (),
                  timeout: Optional[float] = None, progress: Optional[bool] = None) -> Dict:
    """Compile ``sources`` with the harness for ``target``, run every row of ``vectors``
    (int64 array (N, n_in), values must fit int32) on the simulator and return the
    results (see module docstring).

    opt: optimisation flag for avr-gcc ("-Os", "-O2", ...); ignored for pic18 (use
    extra_cflags for SDCC options).  batch_size: vectors per simulator run (default 512
    on avr, 256 on pic18).  timeout: seconds per simulator run (default 120 + 0.5/vector).
    progress: show a tqdm bar (None = only on a terminal).
    """
    if vectors is None:
        raise TargetError("no vectors given")
    sources = [Path(s) for s in sources]
    include_dirs = [Path(d) for d in include_dirs]
    if target == "avr":
        from .avr import DEFAULT_BATCH, run_avr
        return run_avr(sources, include_dirs, name, vectors, opt=opt, workdir=workdir,
                       n_out=n_out, batch_size=batch_size or DEFAULT_BATCH,
                       extra_cflags=extra_cflags, timeout=timeout, progress=progress)
    if target == "pic18":
        from .pic18 import DEFAULT_BATCH, run_pic18
        return run_pic18(sources, include_dirs, name, vectors, workdir=workdir, n_out=n_out,
                         batch_size=batch_size or DEFAULT_BATCH, extra_cflags=extra_cflags,
                         timeout=timeout, progress=progress)
    raise TargetError(f"unknown target {target!r} (known: {', '.join(TARGETS)})")
