"""The MAC kernels the code generator offers, and rendering a model's C with one of them."""

from __future__ import annotations

import inspect
from pathlib import Path

from nnik.estimate.calibrations import DEFAULT_KERNEL_KEY, REPO_ROOT


def accepts(fn, name: str) -> bool:
    try:
        return name in inspect.signature(fn).parameters
    except (TypeError, ValueError):
        return False


def kernel_options() -> list[str | None]:
    """Kernel choices the code generator offers ([None] when it has no kernel option)."""
    from nnik import export, fixedpoint

    if not (accepts(export.render_model_c, "kernel") or accepts(fixedpoint.quantize, "kernel")):
        return [None]
    try:
        from nnik import kernel as kmod
    except ImportError:
        kmod = None
    for mod in (kmod, export, fixedpoint):
        for attr in ("KERNELS", "KERNEL_CHOICES", "KERNEL_OPTIONS"):
            opts = getattr(mod, attr, None)
            if opts:
                return list(opts)
    return ["portable", "fast"]


def default_kernel() -> str | None:
    from nnik import export, fixedpoint

    try:
        from nnik import kernel as kmod

        if getattr(kmod, "DEFAULT_KERNEL", None):
            return str(kmod.DEFAULT_KERNEL)
    except ImportError:
        pass
    for fn in (export.render_model_c, fixedpoint.quantize):
        if accepts(fn, "kernel"):
            d = inspect.signature(fn).parameters["kernel"].default
            if d is not inspect.Parameter.empty and d is not None:
                return str(d)
    opts = kernel_options()
    return opts[0]


def kernel_key(kernel: str | None) -> str:
    return DEFAULT_KERNEL_KEY if kernel is None else str(kernel)


def model_kernel(im, kernel: str | None = None) -> str | None:
    if kernel is not None:
        return kernel
    k = getattr(im, "kernel", None)
    return k if k is not None else default_kernel()


def render_c(im, source: str = "nnik.estimate", kernel: str | None = None) -> dict[str, str]:
    """render_model_c with the kernel option when the generator has one."""
    from nnik.export import render_model_c

    if kernel is not None and accepts(render_model_c, "kernel"):
        return render_model_c(im, source, kernel=kernel)
    return render_model_c(im, source)


def write_c(im, outdir: Path, kernel: str | None = None) -> Path:
    from nnik.export import write_sources

    write_sources(render_c(im, kernel=kernel), outdir)
    rt = REPO_ROOT / "codegen" / "runtime"
    for extra in rt.glob("*.h"):  # e.g. a kernel header next to nnik_flash.h
        if not (outdir / extra.name).exists():
            (outdir / extra.name).write_bytes(extra.read_bytes())
    return outdir / f"{im.name}.c"
