"""The MAC kernels the code generator offers, and rendering a model's C with one of them."""

from __future__ import annotations

from pathlib import Path

from nnik.implementations.mlp import kernel as kmod
from nnik.emit.templating import write_sources
from nnik.implementations.mlp.export import render_model_c
from nnik.emit.templating import RUNTIME
from nnik.implementations.mlp.cost.calibrations import DEFAULT_KERNEL_KEY


def kernel_options() -> list[str]:
    """Kernel choices the code generator offers."""
    return list(kmod.KERNELS)


def default_kernel() -> str:
    return kmod.DEFAULT_KERNEL


def kernel_key(kernel: str | None) -> str:
    return DEFAULT_KERNEL_KEY if kernel is None else str(kernel)


def model_kernel(im, kernel: str | None = None) -> str | None:
    if kernel is not None:
        return kernel
    k = getattr(im, "kernel", None)
    return k if k is not None else default_kernel()


def render_c(im, source: str = "nnik.implementations.mlp.cost", kernel: str | None = None) -> dict[str, str]:
    """{filename: text} of the model's C (kernel None: the model's own)."""
    return render_model_c(im, source, kernel=kernel)


def write_c(im, outdir: Path, kernel: str | None = None) -> Path:
    write_sources(render_c(im, kernel=kernel), outdir)
    for extra in RUNTIME.glob("*.h"):  # e.g. a kernel header next to nnik_flash.h
        if not (outdir / extra.name).exists():
            (outdir / extra.name).write_bytes(extra.read_bytes())
    return outdir / f"{im.name}.c"
