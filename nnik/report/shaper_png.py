"""The picture `nnik shaper-calibrate` draws, laid out as Klipper's calibrate_shaper.py draws its
own: the normalised PSD per accelerometer axis and summed (left scale), each fitted shaper's
vibration reduction over frequency (right scale; the recommended one bold), the PSD after it, and
the fitted resonance marked."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from nnik.dynamics.shaper_figures import MAX_FREQ, normalize_psd  # noqa: E402
from nnik.files.atomic_write import write_file_atomic  # noqa: E402


def shaper_png(path: Path, name: str, cal) -> Path:
    sp = cal.spectrum
    keep = sp.freqs <= MAX_FREQ
    f = sp.freqs[keep]
    psd = {k: normalize_psd(sp.freqs, sp.psd[:, i])[keep] for i, k in enumerate(("X", "Y", "Z", "X+Y+Z"))}
    fig, ax = plt.subplots(figsize=(10, 6), dpi=100)
    for (label, p), color in zip(psd.items(), ("red", "green", "blue", "purple")):
        ax.plot(f, p, label=label, color=color, lw=1.6 if label == "X+Y+Z" else 1.0)
    ax.set_xlabel("Frequency, Hz")
    ax.set_ylabel("Power spectral density (normalised)")
    ax.set_xlim(0, MAX_FREQ)
    ax.set_ylim(bottom=0)
    ax.ticklabel_format(axis="y", style="scientific", scilimits=(0, 0))
    ax.grid(which="major", color="grey")
    ax.minorticks_on()
    ax.grid(which="minor", color="lightgrey")
    res = cal.resonance
    ax.axvline(res.f_hz, color="black", lw=0.8, ls=":", label=f"resonance {res.f_hz:.1f} Hz, damping {res.zeta:.3f}")
    ax2 = ax.twinx()
    ax2.set_ylabel("Shaper vibration reduction (ratio)")
    best = cal.best
    for kind, fit in cal.fits.items():
        sel = kind == best.kind
        label = (f"{kind.upper()} ({fit.freq_hz:.1f} Hz, vibr={100 * fit.vibration:.1f}%, sm~={fit.smoothing_mm:.2f}, "
                 f"accel<={round(fit.max_accel_mm_s2 / 100) * 100:.0f})")
        vals = fit.vals[: len(f)]
        ax2.plot(f[: len(vals)], vals, ls="dashdot" if sel else "dashed", lw=2.0 if sel else 1.0, label=label)
    after = psd["X+Y+Z"][: len(best.vals)] * best.vals[: len(f)]
    ax.plot(f[: len(after)], after, color="cyan", label="After shaper")
    ax2.plot([], [], " ", label=f"Recommended shaper: {best.kind.upper()} @ {best.freq_hz:.1f} Hz")
    ax2.set_ylim(bottom=0)
    ax.legend(loc="upper left", fontsize="x-small")
    ax2.legend(loc="upper right", fontsize="x-small")
    ax.set_title(f"Frequency response and shapers ({name})")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    write_file_atomic(Path(path), buf.getvalue())
    return Path(path)

