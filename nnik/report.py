"""The accuracy/latency report: what a user looks at before flashing.

:func:`write_report` reads whatever the pipeline has left in MODEL_DIR (``metrics.json`` is
required; ``model.pt``, ``data.npz`` and ``fixed_eval.npz`` are used when present) and writes
``index.html`` (self-contained: inline CSS, no scripts, PNGs beside it), ``report.md`` and the
PNGs into OUT_DIR (default ``MODEL_DIR/report``).

Nothing is left out silently: a section whose inputs are missing is shown as "not run" with the
reason. Every number taken from metrics.json sits in a ``<td>`` carrying the raw value in
``data-value`` and its place in metrics.json in ``data-key`` (``/``-separated, e.g.
``float/max_abs/0``); numbers computed here (physical units, µs, differences) carry
``data-value`` only.
"""

from __future__ import annotations

import datetime as _dt
import html
import importlib
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from nnik.errors import NnikError

REPORT_DIRNAME = "report"
METRICS_FILE = "metrics.json"
MODEL_FILE = "model.pt"
DATA_FILE = "data.npz"
FIXED_EVAL_FILE = "fixed_eval.npz"
FIXED_EVAL_ARRAYS = ("p_test", "q_true", "q_float", "q_fixed", "q_delivered")
TEMPLATE = "report.html.j2"
TEMPLATE_DIR = Path(__file__).resolve().parent / "templates"

# The targets a user expects to see, even when they were not run; others in metrics.json follow.
EXPECTED_TARGETS = ("avr", "pic18")

PNG_ERROR_MAP = "error_map.png"
PNG_ERROR_HIST = "error_hist.png"
PNG_TANH = "tanh_error.png"
PNG_TRAINING = "training_curve.png"
PNG_COST = "cost_accuracy.png"
ALL_PNGS = (PNG_ERROR_MAP, PNG_ERROR_HIST, PNG_TANH, PNG_TRAINING, PNG_COST)

GRID_N = 161  # regular grid (per axis) for the float heatmap of an analytic mechanism

# Decimals per kind of number (fixed, so tests and eyes can compare).
D_UNIT = 4  # errors in microsteps / LSB
D_DEG = 5  # errors in degrees
D_UM = 2  # micrometres
D_PCT = 4  # relative errors, %
D_LSB = 3  # tanh errors in LSB of Q15
D_CYC = 0  # cycles, bytes
D_US = 1  # microseconds
D_MS = 2  # milliseconds
D_DIFF = 1  # estimate vs measured, %
D_SEC = 1  # seconds

# ---- published references (labelled as such wherever shown) -------------------------------
PUB_000_SETUP = "PIC18F452, CCS compiler, 16 MHz clock (4 MIPS)"
PUB_000_MIPS = 4.0e6
PUB_000 = (  # (method, ROM words, time ms)
    ("IK with math.h", 1977, 258.6),
    ("MLP with math.h tanh", 2696, 38.0),
    ("MLP with polynomial tanh", 3590, 7.2),
)
PUB_004 = (  # (row, q1, q2, x, y) relative error, %
    ("without normalisation", 5.1851, 1.1009, 5.0147, 13.6855),
    ("with input normalisation to [0, 1]", 0.0508, 0.1017, 0.0807, 0.2008),
)
PUB_TANH = (  # (source, what, value, unit)
    ("seed 000 (CBA 2012), eq. 10-14", "piecewise degree-5 polynomials, float RMS", 1.7362e-5, "abs"),
    ("CMSIS-NN / TFLM int16 table + interpolation", "max error", 1.48, "LSB"),
    ("AIfES Q7 PLAN tanh", "max error", 0.038, "abs"),
    ("256-entry table indexed by Q3.4", "max error", 0.063, "abs"),
)
Q15 = 32768.0


# ============================================================================================
# the document model: cells, tables, figures, sections
# ============================================================================================


@dataclass
class Cell:
    text: str
    value: float | int | None = None  # raw number -> data-value
    key: str | None = None  # place in metrics.json -> data-key
    cls: str = ""
    colspan: int = 1
    rowspan: int = 1
    title: str = ""

    @property
    def data_value(self) -> str | None:
        if self.value is None:
            return None
        if isinstance(self.value, (bool, np.bool_)):
            return str(bool(self.value)).lower()
        if isinstance(self.value, (int, np.integer)):
            return str(int(self.value))
        return repr(float(self.value))


@dataclass
class Table:
    id: str
    title: str
    header: list[str]
    rows: list[list[Cell]] = field(default_factory=list)
    note: str = ""


@dataclass
class Fig:
    file: str
    alt: str
    caption: str


@dataclass
class Section:
    id: str
    title: str
    paragraphs: list[str] = field(default_factory=list)
    not_run: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Fig] = field(default_factory=list)
    verdicts: list[tuple[str, str]] = field(default_factory=list)  # (cls "good"|"bad"|"info", text)


def _finite(v) -> bool:
    try:
        return v is not None and not isinstance(v, bool) and math.isfinite(float(v))
    except (TypeError, ValueError):
        return False


def fmt(v, digits: int | str) -> str:
    """A number with a fixed number of decimals ("sci" for scientific); '—' when absent."""
    if not _finite(v):
        return "—" if v is None else str(v)
    if digits == "sci":
        return f"{float(v):.2e}"
    return f"{float(v):.{int(digits)}f}"


def num(v, digits: int | str, key: str | None = None, cls: str = "num", title: str = "") -> Cell:
    if not _finite(v):
        return Cell("—", cls="num missing", title=title)
    return Cell(fmt(v, digits), value=v, key=key, cls=cls, title=title)


def txt(s: Any, cls: str = "", colspan: int = 1, rowspan: int = 1, title: str = "") -> Cell:
    return Cell("—" if s is None else str(s), cls=cls, colspan=colspan, rowspan=rowspan, title=title)


def not_run_cell(reason: str, colspan: int) -> Cell:
    return Cell(f"not run — {reason}", cls="notrun", colspan=colspan)


def _get(d: Any, *path, default=None):
    for p in path:
        if isinstance(d, dict) and p in d:
            d = d[p]
        elif isinstance(d, list) and isinstance(p, int) and -len(d) <= p < len(d):
            d = d[p]
        else:
            return default
    return d


def _key(*path) -> str:
    return "/".join(str(p) for p in path)


# ============================================================================================
# inputs
# ============================================================================================


@dataclass
class Inputs:
    model_dir: Path
    metrics: dict
    model: Any = None  # nnik.train.TrainedModel
    model_reason: str = ""
    scenario: Any = None  # nnik.scenario.Scenario
    scenario_reason: str = ""
    data: Any = None  # nnik.data.Dataset
    data_reason: str = ""
    fixed_eval: dict | None = None
    fixed_eval_reason: str = ""
    files: list[tuple[str, bool, str]] = field(default_factory=list)  # (file, present, note)


def load_metrics(model_dir: Path) -> dict:
    path = Path(model_dir) / METRICS_FILE
    if not path.is_file():
        raise NnikError("metrics.json not found (run `nnik run` or `nnik evaluate` first)", str(path))
    try:
        metrics = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise NnikError(f"malformed metrics.json: {exc}", str(path)) from None
    if not isinstance(metrics, dict):
        raise NnikError("malformed metrics.json: not a JSON object", str(path))
    for k in ("name", "outputs", "unit"):
        if k not in metrics:
            raise NnikError(f"malformed metrics.json: missing {k!r}", str(path))
    return metrics


def _short_exc(exc: BaseException) -> str:
    s = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {s[0]}" if s else type(exc).__name__


def load_inputs(model_dir: Path) -> Inputs:
    model_dir = Path(model_dir)
    inp = Inputs(model_dir, load_metrics(model_dir))
    inp.files.append((METRICS_FILE, True, "required"))

    mp = model_dir / MODEL_FILE
    if mp.is_file():
        try:
            from nnik.train import TrainedModel

            inp.model = TrainedModel.load(mp)
            inp.scenario = inp.model.scenario
            inp.files.append((MODEL_FILE, True, "weights, scaling, scenario, training history"))
        except Exception as exc:  # noqa: BLE001 - a report must survive a bad model file
            inp.model_reason = f"{MODEL_FILE} could not be loaded ({_short_exc(exc)})"
            inp.files.append((MODEL_FILE, False, inp.model_reason))
    else:
        inp.model_reason = f"{MODEL_FILE} not found in {model_dir}"
        inp.files.append((MODEL_FILE, False, "not found"))

    if inp.scenario is None:
        src = inp.metrics.get("scenario")
        if src and Path(src).is_file():
            try:
                from nnik.scenario import load_scenario

                inp.scenario = load_scenario(src)
            except Exception as exc:  # noqa: BLE001
                inp.scenario_reason = f"scenario {src} could not be loaded ({_short_exc(exc)})"
        else:
            inp.scenario_reason = f"{inp.model_reason or 'no model'}, and the scenario file {src!r} is not found"

    dp = model_dir / DATA_FILE
    if dp.is_file():
        try:
            from nnik.data import Dataset

            inp.data = Dataset.load(dp)
            inp.files.append((DATA_FILE, True, "test split"))
        except Exception as exc:  # noqa: BLE001
            inp.data_reason = f"{DATA_FILE} could not be loaded ({_short_exc(exc)})"
            inp.files.append((DATA_FILE, False, inp.data_reason))
    else:
        inp.data_reason = f"{DATA_FILE} not found in {model_dir}"
        inp.files.append((DATA_FILE, False, "not found"))

    fp = model_dir / FIXED_EVAL_FILE
    if fp.is_file():
        try:
            with np.load(fp) as z:
                missing = [a for a in FIXED_EVAL_ARRAYS if a not in z.files]
                if missing:
                    raise ValueError(f"missing arrays {', '.join(missing)}")
                fe = {a: np.asarray(z[a], dtype=np.float64) for a in FIXED_EVAL_ARRAYS}
            n = len(fe["p_test"])
            if any(a.ndim != 2 or len(a) != n for a in fe.values()) or n == 0:
                raise ValueError("arrays must be (N, 2) with the same N > 0")
            inp.fixed_eval = fe
            inp.files.append((FIXED_EVAL_FILE, True, f"{n} points of the fixed-point evaluation"))
        except Exception as exc:  # noqa: BLE001
            inp.fixed_eval_reason = f"{FIXED_EVAL_FILE} could not be read ({_short_exc(exc)})"
            inp.files.append((FIXED_EVAL_FILE, False, inp.fixed_eval_reason))
    else:
        inp.fixed_eval_reason = f"{FIXED_EVAL_FILE} not found in {model_dir}"
        inp.files.append((FIXED_EVAL_FILE, False, "not found (fixed-point export not run)"))
    return inp


# ============================================================================================
# units
# ============================================================================================


@dataclass
class Phys:
    """Physical size of one actuator unit, per output."""

    label: str  # "mech. deg" | "belt µm"
    factors: list[float]
    digits: int
    resolution: str  # human description for the scenario table


def physical_units(scn, n_out: int) -> tuple[Phys | None, str]:
    """(Phys, "") or (None, reason)."""
    if scn is None:
        return None, "scenario unavailable"
    act = scn.actuator
    fam = getattr(scn.mechanism, "family", "")
    unit = act.unit
    if fam == "galvo":
        deg = math.degrees(1.0 / act.units_per_rad)
        return Phys("mech. deg", [deg] * n_out, D_DEG,
                    f"{deg:.6g} mechanical deg per {unit} ({2 * deg:.6g} deg optical)"), ""
    if fam == "belt":
        radii = np.asarray(scn.mechanism.radii, dtype=np.float64)
        um = (radii * 1000.0 / act.units_per_rad).tolist()
        per_rev = act.params["steps_per_rev"] * act.params["microsteps"]
        res = " / ".join(f"{u:.4g}" for u in um)
        return Phys("belt µm", um[:n_out], D_UM,
                    f"{res} µm of belt per {unit} (2πR / {per_rev}, R = "
                    f"{' / '.join(f'{r:.4g}' for r in radii)} mm)"), ""
    if fam == "measured" and act.kind == "stepper" and act.params.get("mm_per_rev"):
        per_rev = act.params["steps_per_rev"] * act.params["microsteps"]
        um = act.params["mm_per_rev"] * 1000.0 / per_rev
        return Phys("belt µm", [um] * n_out, D_UM,
                    f"{um:.4g} µm of belt per {unit} ({act.params['mm_per_rev']:g} mm/rev / {per_rev})"), ""
    return None, f"no physical size known for one {unit} of a {fam or 'this'} machine"


# ============================================================================================
# target helpers
# ============================================================================================


def target_names(metrics: dict) -> list[str]:
    names = list(EXPECTED_TARGETS)
    for t in (metrics.get("targets") or {}):
        if t not in names:
            names.append(t)
    return names


def target_status(metrics: dict, t: str) -> tuple[dict | None, str]:
    """(target dict, "") when it ran, else (None, reason)."""
    targets = metrics.get("targets")
    if not isinstance(targets, dict):
        return None, "no `targets` section in metrics.json"
    tm = targets.get(t)
    if not isinstance(tm, dict):
        return None, f"no `{t}` entry in the `targets` section of metrics.json"
    if "not_run" in tm:
        return None, str(tm["not_run"])
    return tm, ""


def clocks_per_cycle(t: str, tm: dict) -> int:
    """PIC18 counts instruction cycles (4 clocks each); AVR counts clocks. Overridable."""
    return int(tm.get("clocks_per_cycle", 4 if t.lower().startswith("pic") else 1))


def cycles_to_us(cycles, t: str, tm: dict) -> float | None:
    clock = tm.get("clock_hz")
    if not (_finite(cycles) and _finite(clock) and clock > 0):
        return None
    return float(cycles) * clocks_per_cycle(t, tm) / float(clock) * 1e6


def _pct_diff(est, meas) -> float | None:
    if not (_finite(est) and _finite(meas)) or meas == 0:
        return None
    return (float(est) - float(meas)) / float(meas) * 100.0


def mlp_error(metrics: dict) -> tuple[list[float] | None, str | None]:
    """Max error per output of the shipped fixed-point MLP as the chip delivers it."""
    fx = metrics.get("fixed")
    if not isinstance(fx, dict):
        return None, None
    if isinstance(fx.get("delivered_max_abs"), list):
        return fx["delivered_max_abs"], "fixed/delivered_max_abs"
    if isinstance(fx.get("max_abs"), list):
        return fx["max_abs"], "fixed/max_abs"
    return None, None


def implementations(metrics: dict, t: str, tm: dict) -> list[dict]:
    """Every measured implementation on a target: the nnik MLP, MLP kernels, float IK, LUT.

    Each: label, kind, keypath (tuple into metrics), cycles, flash, ram, err (list or None),
    err_key (metrics key prefix of err, or None).
    """
    out = []
    err, err_key = mlp_error(metrics)
    variant = _get(metrics, "fixed", "tanh_variant") or _get(metrics, "tanh", "variant")
    out.append(dict(label="nnik MLP" + (f" ({variant} tanh)" if variant else ""), kind="mlp",
                    keypath=("targets", t), cycles=tm.get("cycles"), flash=tm.get("flash_bytes"),
                    ram=tm.get("ram_bytes"), err=err, err_key=err_key))
    for name, k in (tm.get("kernels") or {}).items():
        if isinstance(k, dict):
            out.append(dict(label=f"MLP kernel {name}", kind="kernel", keypath=("targets", t, "kernels", name),
                            cycles=k.get("cycles"), flash=k.get("flash_bytes"), ram=k.get("ram_bytes"),
                            err=k.get("max_abs"), err_key=_key("targets", t, "kernels", name, "max_abs")))
    for bname, label, kind in (("float", "float IK with math.h", "float"), ("lut", "LUT baseline", "lut")):
        b = _get(tm, "baselines", bname)
        if isinstance(b, dict):
            out.append(dict(label=label, kind=kind, keypath=("targets", t, "baselines", bname),
                            cycles=b.get("cycles"), flash=b.get("flash_bytes"), ram=b.get("ram_bytes"),
                            err=b.get("max_abs"), err_key=_key("targets", t, "baselines", bname, "max_abs")))
    return out


def _worst(err) -> float | None:
    if not isinstance(err, (list, tuple)) or not err or not all(_finite(e) for e in err):
        return None
    return float(max(err))


def lut_verdicts(metrics: dict) -> tuple[list[str], list[str]]:
    """(sentences where the LUT wins, sentences where it was compared and does not)."""
    unit = metrics.get("unit", "")
    wins, losses = [], []
    for t in target_names(metrics):
        tm, _ = target_status(metrics, t)
        if tm is None:
            continue
        impls = implementations(metrics, t, tm)
        lut = next((i for i in impls if i["kind"] == "lut"), None)
        if lut is None or not _finite(lut["cycles"]) or _worst(lut["err"]) is None:
            continue
        le = _worst(lut["err"])
        beaten = []
        for i in impls:
            if i["kind"] not in ("mlp", "kernel") or not _finite(i["cycles"]) or _worst(i["err"]) is None:
                continue
            if float(lut["cycles"]) < float(i["cycles"]) and le < _worst(i["err"]):
                beaten.append(i)
        if beaten:
            for i in beaten:
                wins.append(
                    f"On {t} the LUT baseline wins over the {i['label']}: fewer cycles "
                    f"({fmt(lut['cycles'], D_CYC)} vs {fmt(i['cycles'], D_CYC)}) and lower max error "
                    f"({fmt(le, D_UNIT)} vs {fmt(_worst(i['err']), D_UNIT)} {unit}), at "
                    f"{fmt(lut['flash'], D_CYC)} vs {fmt(i['flash'], D_CYC)} bytes of flash. "
                    "On this machine, consider flashing the table instead."
                )
        else:
            losses.append(f"On {t} the LUT baseline ({fmt(lut['cycles'], D_CYC)} cycles, max error "
                          f"{fmt(le, D_UNIT)} {unit}) is not both faster and more accurate than any MLP variant.")
    return wins, losses


# ============================================================================================
# summary (terminal)
# ============================================================================================

SUMMARY_HEADER = ("item", "result", "detail")


def _vec(v, digits=D_UNIT) -> str:
    if not isinstance(v, (list, tuple)):
        return "—"
    return " / ".join(fmt(x, digits) for x in v)


def summary_rows(metrics: dict) -> list[tuple[str, ...]]:
    """A compact table for the terminal: (item, result, detail) per row, every part shown.

    Columns are SUMMARY_HEADER. Missing sections appear as ("...", "not run", reason).
    """
    unit = metrics.get("unit", "")
    rows: list[tuple[str, ...]] = []
    net = metrics.get("network") or {}
    shape = "-".join(map(str, net.get("shape", []))) or "?"
    rows.append(("scenario", str(metrics.get("name", "?")),
                 f"{metrics.get('mechanism', '?')}; {shape} {net.get('mode', '')} MLP, "
                 f"{net.get('parameters', '?')} parameters"))
    n_test = _get(metrics, "dataset", "n_test")
    truth = _get(metrics, "dataset", "truth", default="truth")
    aff = metrics.get("affine_only")
    if isinstance(aff, dict):
        rows.append(("affine baseline", f"max {_vec(aff.get('max_abs'))} {unit}", f"RMS {_vec(aff.get('rms'))}"))
    fl = metrics.get("float")
    if isinstance(fl, dict):
        pos = fl.get("position_um")
        extra = f"; position max {fmt(pos.get('max'), D_UM)} µm" if isinstance(pos, dict) else ""
        rows.append(("float64 MLP", f"max {_vec(fl.get('max_abs'))} {unit}",
                     f"RMS {_vec(fl.get('rms'))}; vs {truth}, {n_test} points{extra}"))
    else:
        rows.append(("float64 MLP", "not run", "no `float` section in metrics.json"))
    fx = metrics.get("fixed")
    if isinstance(fx, dict):
        rows.append(("fixed point (host model)", f"max {_vec(fx.get('max_abs'))} {unit}",
                     f"delivered max {_vec(fx.get('delivered_max_abs'))}; "
                     f"tanh {fx.get('tanh_variant', '?')}; {fx.get('weights_bytes', '?')} weight bytes"))
    else:
        rows.append(("fixed point (host model)", "not run", "no `fixed` section in metrics.json"))
    host = metrics.get("host")
    if isinstance(host, dict):
        ok = bool(host.get("bit_exact"))
        rows.append(("C on host", "bit-exact" if ok else "NOT bit-exact",
                     f"{host.get('mismatches', '?')} mismatches over {host.get('points', '?')} points"))
    else:
        rows.append(("C on host", "not run", "no `host` section in metrics.json"))
    th = metrics.get("tanh")
    if isinstance(th, dict):
        rows.append(("integer tanh", str(th.get("variant", "?")),
                     f"max {fmt(th.get('max_lsb'), D_LSB)} LSB, RMS {fmt(th.get('rms_lsb'), D_LSB)} LSB of Q15"))
    else:
        rows.append(("integer tanh", "not run", "no `tanh` section in metrics.json"))
    for t in target_names(metrics):
        tm, reason = target_status(metrics, t)
        if tm is None:
            rows.append((t, "not run", reason))
            continue
        us = cycles_to_us(tm.get("cycles"), t, tm)
        clock = tm.get("clock_hz")
        mhz = f" @ {float(clock) / 1e6:g} MHz" if _finite(clock) else ""
        exact = "bit-exact" if tm.get("bit_exact") else f"NOT bit-exact ({tm.get('mismatches', '?')} mismatches)"
        rows.append((t, f"{fmt(tm.get('cycles'), D_CYC)} cycles = {fmt(us, D_US)} µs{mhz}",
                     f"flash {fmt(tm.get('flash_bytes'), D_CYC)} B, RAM {fmt(tm.get('ram_bytes'), D_CYC)} B, {exact}"))
    wins, _ = lut_verdicts(metrics)
    if wins:
        rows.append(("LUT baseline", "wins", wins[0] + (f" (and {len(wins) - 1} more)" if len(wins) > 1 else "")))
    onnx = metrics.get("onnx")
    if isinstance(onnx, dict):
        rows.append(("ONNX vs torch", "ok" if onnx.get("ok") else "FAILED",
                     f"max |diff| {fmt(onnx.get('max_abs_diff'), 'sci')} (tolerance {onnx.get('tolerance', '?')})"))
    return rows


# ============================================================================================
# sections
# ============================================================================================


class _Builder:
    def __init__(self, inp: Inputs, out_dir: Path):
        self.inp = inp
        self.m = inp.metrics
        self.out = out_dir
        self.outputs = list(self.m["outputs"])
        self.n_out = len(self.outputs)
        self.unit = self.m["unit"]
        self.phys, self.phys_reason = physical_units(inp.scenario, self.n_out)
        self.analytic = bool(getattr(getattr(inp.scenario, "mechanism", None), "analytic", False))
        self.derived_fixed = self._derived_fixed()

    # ---- shared -------------------------------------------------------------------------------

    def _plot(self, sec: Section, fn: Callable[[], Fig | str]) -> None:
        """Run a plot; a string result (or an exception) is a reason shown as "not run"."""
        try:
            r = fn()
        except Exception as exc:  # noqa: BLE001 - one broken picture must not sink the report
            r = f"picture failed ({_short_exc(exc)})"
        if isinstance(r, Fig):
            sec.figures.append(r)
        else:
            sec.not_run.append(r)

    def _derived_fixed(self) -> dict | None:
        """RMS/p99 of the delivered commands and position errors, from fixed_eval.npz."""
        fe = self.inp.fixed_eval
        if fe is None:
            return None
        e = np.abs(fe["q_delivered"] - fe["q_true"])
        d = {"rms": np.sqrt((e**2).mean(0)).tolist(), "p99": np.percentile(e, 99, axis=0).tolist(),
             "max": e.max(0).tolist(), "position_um": None}
        scn = self.inp.scenario
        if scn is not None and self.analytic:
            try:
                from nnik.evaluate import position_error_um

                d["position_um"] = position_error_um(scn, fe["q_delivered"], fe["p_test"])
            except Exception:  # noqa: BLE001
                d["position_um"] = None
        return d

    # ---- 1. scenario --------------------------------------------------------------------------

    def scenario(self) -> Section:
        m, scn = self.m, self.inp.scenario
        sec = Section("scenario", "Scenario")
        t = Table("scenario-table", "Machine, actuator and network", ["item", "value"])
        add = lambda k, v: t.rows.append([txt(k, "key"), v if isinstance(v, Cell) else txt(v)])  # noqa: E731
        add("name", m.get("name"))
        if scn is not None and scn.raw.get("description"):
            add("description", scn.raw.get("description"))
        add("scenario file", m.get("scenario"))
        add("mechanism", m.get("mechanism"))
        if scn is not None:
            mech = scn.mechanism
            params = {k: v for k, v in mech.params.items() if v is not None and k not in ("distortion", "csv")}
            add("mechanism kind", f"{mech.kind} ({mech.family})")
            add("parameters", ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}"
                                        for k, v in params.items()) or "—")
            dist = getattr(mech, "dist", None)
            if dist:
                add("distortion", ", ".join(f"{k} = {v:g}" for k, v in dist.items()))
            if mech.family == "measured":
                add("measurements", f"{Path(mech.params.get('csv', '?')).name} ({len(mech.positions_mm)} rows)")
            ws = scn.workspace
            add("workspace", f"x {ws.x_mm[0]:g} … {ws.x_mm[1]:g} mm, y {ws.y_mm[0]:g} … {ws.y_mm[1]:g} mm "
                             f"({ws.x_mm[1] - ws.x_mm[0]:g} × {ws.y_mm[1] - ws.y_mm[0]:g} mm)")
        else:
            add("parameters / workspace", Cell(f"not available — {self.inp.scenario_reason}", cls="notrun"))
        add("actuator", m.get("actuator"))
        if self.phys is not None:
            add("actuator resolution", self.phys.resolution)
        else:
            add("actuator resolution", Cell(f"not available — {self.phys_reason}", cls="notrun"))
        add("outputs", ", ".join(f"{o} ({self.unit})" for o in self.outputs))
        net = m.get("network") or {}
        add("network", f"{'-'.join(map(str, net.get('shape', [])))} tanh MLP, {net.get('mode', '?')} mode, "
                       f"inputs {'normalised to [-1, 1]' if net.get('normalize') else 'raw mm (not normalised)'}")
        add("weights (count)", num(net.get("parameters"), 0, "network/parameters"))
        wb = _get(m, "fixed", "weights_bytes")
        if wb is not None:
            add("weights (bytes, fixed point)", num(wb, 0, "fixed/weights_bytes"))
        else:
            add("weights (bytes, fixed point)", Cell("not run — no `fixed` section in metrics.json", cls="notrun"))
        ds = m.get("dataset") or {}
        add("data", f"{ds.get('n_train', '?')} train, {ds.get('n_val', '?')} validation, "
                    f"{ds.get('n_test', '?')} test points; truth: {ds.get('truth', '?')}")
        sec.tables.append(t)
        return sec

    # ---- 2. accuracy --------------------------------------------------------------------------

    def _err_rows(self, label: str, vals: dict, keys: dict, note: str = "", note_cls: str = "") -> list[list[Cell]]:
        """One row per output: label | output | max RMS p99 (unit) | phys unit | max RMS p99 | note."""
        rows = []
        for j, o in enumerate(self.outputs):
            r = [txt(label, "label", rowspan=self.n_out)] if j == 0 else []
            r.append(txt(o))
            for s in ("max", "rms", "p99"):
                v = _get(vals.get(s), j)
                r.append(num(v, D_UNIT, f"{keys[s]}/{j}" if keys.get(s) and v is not None else None))
            if self.phys is not None:
                r.append(txt(self.phys.label))
                for s in ("max", "rms", "p99"):
                    v = _get(vals.get(s), j)
                    r.append(num(None if v is None else float(v) * self.phys.factors[j], self.phys.digits,
                                 cls="num derived"))
            else:
                r += [txt("—"), num(None, 0), num(None, 0), num(None, 0)]
            if j == 0:
                r.append(txt(note, note_cls, rowspan=self.n_out))
            rows.append(r)
        return rows

    def _pos_row(self, label: str, pos: dict | None, key: str | None, note: str = "") -> list[list[Cell]]:
        if not isinstance(pos, dict):
            return []
        r = [txt(label, "label"), txt("head position"), num(None, 0), num(None, 0), num(None, 0), txt("µm")]
        for s in ("max", "rms", "p99"):
            r.append(num(pos.get(s), D_UM, f"{key}/{s}" if key else None, cls="num" if key else "num derived"))
        r.append(txt(note))
        return [r]

    def _nr_row(self, label: str, reason: str, cls: str = "notrun") -> list[Cell]:
        text = reason if cls == "bad" or " not run" in reason else f"not run — {reason}"
        return [txt(label, "label"), Cell(text, cls=cls, colspan=9)]

    def accuracy(self) -> Section:
        m, unit = self.m, self.unit
        sec = Section("accuracy", "Accuracy")
        ds = m.get("dataset") or {}
        sec.paragraphs.append(
            f"Absolute error against the {ds.get('truth', 'truth')} on {ds.get('n_test', '?')} test points, "
            f"in {unit} and in physical units" + (f" ({self.phys.label})" if self.phys else "") + ". "
            "Physical values are the output error times the actuator resolution; head position errors "
            "(µm) come from the forward kinematics where the machine has an analytic model.")
        if self.phys is None:
            sec.not_run.append(f"physical units not available: {self.phys_reason}")
        hdr = ["model", "output", f"max ({unit})", f"RMS ({unit})", f"p99 ({unit})", "physical unit",
               "max", "RMS", "p99", "note"]
        t = Table("accuracy-table", "Error per output: max, RMS, 99th percentile", hdr)
        aff = m.get("affine_only")
        if isinstance(aff, dict):
            t.rows += self._err_rows("affine least squares (baseline)", {"max": aff.get("max_abs"), "rms": aff.get("rms"),
                                     "p99": aff.get("p99")},
                                     {"max": "affine_only/max_abs", "rms": "affine_only/rms", "p99": "affine_only/p99"},
                                     "a 2×2 map plus offset fitted on the training set")
        fl = m.get("float")
        if isinstance(fl, dict):
            t.rows += self._err_rows("float64 MLP (host)", {"max": fl.get("max_abs"), "rms": fl.get("rms"),
                                     "p99": fl.get("p99")},
                                     {"max": "float/max_abs", "rms": "float/rms", "p99": "float/p99"},
                                     "torch float64; ONNX checked against it")
            t.rows += self._pos_row("float64 MLP (host)", fl.get("position_um"), "float/position_um")
        else:
            t.rows.append(self._nr_row("float64 MLP (host)", "no `float` section in metrics.json"))
        fx = m.get("fixed")
        dfx = self.derived_fixed
        delivered_vals = None
        if isinstance(fx, dict):
            t.rows += self._err_rows("fixed point, integer model (before rounding)",
                                     {"max": fx.get("max_abs"), "rms": fx.get("rms"), "p99": fx.get("p99")},
                                     {"max": "fixed/max_abs", "rms": "fixed/rms", "p99": "fixed/p99"},
                                     f"Python integer model, tanh {fx.get('tanh_variant', '?')}")
            delivered_vals = {"max": fx.get("delivered_max_abs"),
                              "rms": dfx["rms"] if dfx else None, "p99": dfx["p99"] if dfx else None}
            note = "rounded integer commands" + ("" if dfx else f"; RMS/p99 need {FIXED_EVAL_FILE}")
            t.rows += self._err_rows("fixed point, delivered commands", delivered_vals,
                                     {"max": "fixed/delivered_max_abs"}, note)
            if dfx:
                t.rows += self._pos_row("fixed point, delivered commands", dfx.get("position_um"), None,
                                        "forward kinematics of the delivered commands")
        else:
            t.rows.append(self._nr_row("fixed point", "fixed-point export not run: no `fixed` section in metrics.json"))

        def chip_rows(label: str, rec: dict | None, reason: str):
            if rec is None:
                t.rows.append(self._nr_row(label, reason))
            elif not rec.get("bit_exact"):
                t.rows.append(self._nr_row(label, f"NOT bit-exact with the integer model: {rec.get('mismatches', '?')} "
                                                  "mismatches; its errors are unknown — do not flash", "bad"))
            elif delivered_vals is None:
                t.rows.append(self._nr_row(label, "bit-exact, but no `fixed` section to take the errors from"))
            else:
                pts = rec.get("points")
                t.rows.extend(self._err_rows(label, delivered_vals, {"max": "fixed/delivered_max_abs"},
                                             "bit-exact with the integer model" + (f" on {pts} points" if pts else "")
                                             + ": the delivered commands above", "good"))

        host = m.get("host")
        chip_rows("C on host", host if isinstance(host, dict) else None, "no `host` section in metrics.json")
        for tname in target_names(m):
            tm, reason = target_status(m, tname)
            chip_rows(f"C on {tname}", tm, reason)
        sec.tables.append(t)

        # verdict against the physical limit (DOMAIN: <= 0.5 unit means the rounded command is within 1)
        pre, what = None, None
        if isinstance(fx, dict) and isinstance(fx.get("max_abs"), list):
            pre, what = max(fx["max_abs"]), "fixed-point"
        elif isinstance(fl, dict) and isinstance(fl.get("max_abs"), list):
            pre, what = max(fl["max_abs"]), "float"
        if _finite(pre):
            if pre <= 0.5:
                sec.verdicts.append(("good", f"The {what} model's largest error before rounding is "
                                             f"{fmt(pre, D_UNIT)} {unit} ≤ 0.5 {unit}: every rounded command is within 1 "
                                             f"{unit} of the exact one on the test set."))
            else:
                sec.verdicts.append(("bad", f"The {what} model's largest error before rounding is {fmt(pre, D_UNIT)} {unit} "
                                            f"> 0.5 {unit}: some rounded commands are more than 1 {unit} from exact."))
        self._plot(sec, self.plot_error_map)
        self._plot(sec, self.plot_error_hist)
        return sec

    def plot_error_map(self) -> Fig | str:
        from nnik import report_plots as rp

        inp, unit = self.inp, self.unit
        scn = inp.scenario
        ws = scn.workspace if scn is not None else None
        extent = (ws.x_mm[0], ws.x_mm[1], ws.y_mm[0], ws.y_mm[1]) if ws is not None else None
        fe = inp.fixed_eval
        if fe is not None:
            p, err = fe["p_test"], fe["q_fixed"] - fe["q_true"]
            kind = "binned" if len(p) >= 2000 else "points"
            how = "largest |error| per cell over" if kind == "binned" else "at each of"
            title = (f"{self.m['name']}: fixed-point model (before rounding) vs {_truth(self.m)}, "
                     f"{how} {len(p)} test points")
            rp.error_map(self.out / PNG_ERROR_MAP, x=p[:, 0], y=p[:, 1], err=err, outputs=self.outputs, unit=unit,
                         title=title, kind=kind, extent=extent)
            cap = f"Fixed-point error over the workspace ({how} {len(p)} test points); red cross: worst point."
        else:
            if inp.model is None:
                return f"error map not run: {inp.model_reason} and {inp.fixed_eval_reason}"
            if self.analytic:
                from nnik.data import exact_targets

                pts = ws.grid(GRID_N)
                err = (inp.model.predict(pts) - exact_targets(scn, pts)).reshape(GRID_N, GRID_N, -1)
                xs = np.linspace(ws.x_mm[0], ws.x_mm[1], GRID_N)
                ys = np.linspace(ws.y_mm[0], ws.y_mm[1], GRID_N)
                title = (f"{self.m['name']}: FLOAT64 MLP vs exact IK on a {GRID_N}×{GRID_N} grid "
                         "(fixed-point export not run)")
                rp.error_map(self.out / PNG_ERROR_MAP, x=xs, y=ys, err=err, outputs=self.outputs, unit=unit,
                             title=title, kind="grid", extent=extent)
                cap = (f"Float64 MLP error on a regular {GRID_N}×{GRID_N} grid (the fixed-point model was not run: "
                       f"{inp.fixed_eval_reason}); red cross: worst point.")
            else:
                if inp.data is None:
                    return f"error map not run: {inp.data_reason}"
                p, q = inp.data.p["test"], inp.data.q["test"]
                err = inp.model.predict(p) - q
                title = (f"{self.m['name']}: FLOAT64 MLP vs {_truth(self.m)} ({len(p)} points; "
                         "fixed-point export not run)")
                rp.error_map(self.out / PNG_ERROR_MAP, x=p[:, 0], y=p[:, 1], err=err, outputs=self.outputs,
                             unit=unit, title=title, kind="points", extent=extent)
                cap = (f"Float64 MLP error at the {len(p)} held-out measured points (no analytic model, so no grid; "
                       f"fixed-point model not run: {inp.fixed_eval_reason}); red cross: worst point.")
        return Fig(PNG_ERROR_MAP, "error heatmap over the workspace", cap)

    def plot_error_hist(self) -> Fig | str:
        from nnik import report_plots as rp

        inp = self.inp
        fe = inp.fixed_eval
        if fe is not None:
            errors = {"float64 MLP": fe["q_float"] - fe["q_true"],
                      "fixed point (before rounding)": fe["q_fixed"] - fe["q_true"],
                      "delivered integer commands": fe["q_delivered"] - fe["q_true"]}
            title = f"{self.m['name']}: error distribution, float vs fixed point ({len(fe['p_test'])} test points)"
            cap = "Signed error distributions of the float64 MLP, the fixed-point model and the delivered commands."
        else:
            if inp.model is None or inp.data is None:
                return f"error histogram not run: {inp.model_reason or inp.data_reason}"
            p, q = inp.data.p["test"], inp.data.q["test"]
            errors = {"float64 MLP": inp.model.predict(p) - q}
            title = f"{self.m['name']}: error distribution, FLOAT64 MLP only (fixed-point export not run)"
            cap = f"Signed error distribution of the float64 MLP only (fixed point not run: {inp.fixed_eval_reason})."
        rp.error_histogram(self.out / PNG_ERROR_HIST, errors=errors, outputs=self.outputs, unit=self.unit, title=title)
        return Fig(PNG_ERROR_HIST, "error histogram", cap)

    # ---- 3. fixed point and verification ---------------------------------------------------------

    def fixed(self) -> Section:
        m = self.m
        sec = Section("fixed", "Fixed point and bit-exactness")
        fx = m.get("fixed")
        if isinstance(fx, dict):
            t = Table("fixed-table", "Fixed-point export", ["item", "value"])
            t.rows.append([txt("tanh variant", "key"), txt(fx.get("tanh_variant"))])
            t.rows.append([txt("weights (bytes)", "key"), num(fx.get("weights_bytes"), 0, "fixed/weights_bytes")])
            qf = fx.get("q_formats")
            if isinstance(qf, dict):
                for k, v in _flatten(qf):
                    t.rows.append([txt(f"Q format: {k}", "key"), txt(v)])
            sec.tables.append(t)
        else:
            sec.not_run.append("fixed-point export not run: no `fixed` section in metrics.json")
        t = Table("verify-table", "Generated C vs the Python integer model",
                  ["where", "bit-exact", "mismatches", "points", "compiler", "flags"])
        host = m.get("host")
        if isinstance(host, dict):
            ok = bool(host.get("bit_exact"))
            t.rows.append([txt("host", "label"), Cell("yes" if ok else "NO", value=ok, key="host/bit_exact",
                                                      cls="good" if ok else "bad"),
                           num(host.get("mismatches"), 0, "host/mismatches"), num(host.get("points"), 0, "host/points"),
                           txt(host.get("compiler")), txt(host.get("flags"))])
        else:
            t.rows.append([txt("host", "label"), not_run_cell("no `host` section in metrics.json", 5)])
        for tname in target_names(m):
            tm, reason = target_status(m, tname)
            if tm is None:
                t.rows.append([txt(tname, "label"), not_run_cell(reason, 5)])
                continue
            ok = bool(tm.get("bit_exact"))
            t.rows.append([txt(tname, "label"), Cell("yes" if ok else "NO", value=ok, key=_key("targets", tname, "bit_exact"),
                                                     cls="good" if ok else "bad"),
                           num(tm.get("mismatches"), 0, _key("targets", tname, "mismatches")),
                           num(tm.get("points"), 0, _key("targets", tname, "points")),
                           txt(tm.get("compiler")), txt(tm.get("flags"))])
        sec.tables.append(t)
        return sec

    # ---- 4. tanh ---------------------------------------------------------------------------------

    def tanh(self) -> Section:
        m = self.m
        sec = Section("tanh", "Integer tanh")
        th = m.get("tanh") if isinstance(m.get("tanh"), dict) else None
        variant = (th or {}).get("variant") or _get(m, "fixed", "tanh_variant")
        try:
            act = importlib.import_module("nnik.activations")  # optional here
        except Exception as exc:  # noqa: BLE001
            act, act_reason = None, f"nnik.activations could not be imported ({_short_exc(exc)})"
        else:
            act_reason = ""
            for need in ("tanh_int", "VARIANTS", "sweep"):
                if not hasattr(act, need):
                    act, act_reason = None, f"nnik.activations has no `{need}`"
                    break
        default_used = False
        if variant is None and act is not None:
            variant = getattr(act, "DEFAULT_VARIANT", None) or next(iter(act.VARIANTS), None)
            default_used = True
        t = Table("tanh-table", "tanh replacement: error in LSB of Q15 (1 LSB = 2⁻¹⁵ ≈ 3.05e-5)",
                  ["source", "variant", "max (LSB)", "RMS (LSB)", "note"])
        if th is not None:
            t.rows.append([txt("this run (metrics.json)", "label"), txt(th.get("variant")),
                           num(th.get("max_lsb"), D_LSB, "tanh/max_lsb"), num(th.get("rms_lsb"), D_LSB, "tanh/rms_lsb"),
                           txt("all 65536 int16 inputs")])
        else:
            t.rows.append([txt("this run (metrics.json)", "label"),
                           not_run_cell("no `tanh` section in metrics.json", 4)])
        var_obj = None
        if act is not None and variant is not None:
            try:
                var_obj = act.VARIANTS[variant]
                sw = act.sweep(variant)
                note = "recomputed now by nnik.activations.sweep"
                if default_used:
                    note += " for the default variant (no variant named in metrics.json)"
                t.rows.append([txt("recomputed", "label"), txt(variant), num(sw.get("max_lsb"), D_LSB, cls="num derived"),
                               num(sw.get("rms_lsb"), D_LSB, cls="num derived"), txt(note)])
            except Exception as exc:  # noqa: BLE001
                var_obj = None
                act_reason = f"variant {variant!r} not available in nnik.activations ({_short_exc(exc)})"
        for src, what, val, u in PUB_TANH:
            lsb = val if u == "LSB" else val * Q15
            t.rows.append([txt(f"published: {src}", "published"), txt(what), num(lsb, D_LSB, cls="num derived published"),
                           num(None, 0), txt(f"as published: {val:g}" + (" (absolute)" if u == "abs" else " LSB"))])
        t.note = "Published rows are converted to LSB of Q15 here (absolute × 32768); labelled published."
        sec.tables.append(t)
        if act is None:
            sec.not_run.append(f"tanh error plot not available: {act_reason}")
        elif var_obj is None:
            sec.not_run.append(f"tanh error plot not available: {act_reason or 'no variant to plot'}")
        else:
            self._plot(sec, lambda: self.plot_tanh(act, variant, var_obj, default_used))
        return sec

    def plot_tanh(self, act, variant: str, var_obj, default_used: bool) -> Fig:
        from nnik import report_plots as rp

        v = np.arange(-32768, 32768, dtype=np.int64)
        x = v / 4096.0
        ex = np.tanh(x)
        int_err = np.asarray(act.tanh_int(v, variant), dtype=np.float64) - ex * Q15
        if hasattr(act, "tanh_float"):
            fl = np.asarray(act.tanh_float(x, variant), dtype=np.float64)
        else:  # no float pieces exposed: the integer result is all there is
            fl = np.asarray(act.tanh_int(v, variant), dtype=np.float64) / Q15
        float_err = (fl - ex) * Q15
        desc = getattr(var_obj, "description", "")
        title = f"tanh replacement {variant}" + (" (default variant)" if default_used else "")
        if desc:
            title += f"\n{desc}"
        rp.tanh_error(self.out / PNG_TANH, x=x, float_err_lsb=float_err, int_err_lsb=int_err, title=title,
                      sat_x=getattr(var_obj, "sat_x", None))
        return Fig(PNG_TANH, "tanh approximation error", f"Error of {variant} over its whole Q3.12 input range, "
                   "float pieces and integer implementation, in LSB of Q15.")

    # ---- 5. targets: latency, memory, cost vs accuracy --------------------------------------------

    def targets(self) -> Section:
        m, unit = self.m, self.unit
        sec = Section("targets", "Latency and memory on the chips")
        if not isinstance(m.get("targets"), dict):
            sec.not_run.append("targets not run: no `targets` section in metrics.json")
        lat = Table("latency-table", "Latency per IK call (measured in the simulator)",
                    ["target", "clock (MHz)", "cycles (mean)", "cycles (max)", "µs (mean)", "µs (max)",
                     "estimate (cycles)", "estimate vs measured (%)"])
        mem = Table("memory-table", "Memory", ["target", "flash (bytes)", "estimate (bytes)", "difference (%)",
                                              "RAM (bytes)", "estimate (bytes)", "difference (%)"])
        ran = []
        for tname in target_names(m):
            tm, reason = target_status(m, tname)
            if tm is None:
                lat.rows.append([txt(tname, "label"), not_run_cell(reason, 7)])
                mem.rows.append([txt(tname, "label"), not_run_cell(reason, 6)])
                continue
            ran.append((tname, tm))
            k = lambda *p: _key("targets", tname, *p)  # noqa: E731
            est = tm.get("estimate") if isinstance(tm.get("estimate"), dict) else {}
            clock = tm.get("clock_hz")
            cpc = clocks_per_cycle(tname, tm)
            lat.rows.append([
                txt(tname, "label", title=f"{tm.get('compiler', '')} {tm.get('flags', '')}".strip()),
                num(None if not _finite(clock) else clock / 1e6, 3, cls="num derived",
                    title=f"{cpc} clock(s) per counted cycle"),
                num(tm.get("cycles"), D_CYC, k("cycles")), num(tm.get("cycles_max"), D_CYC, k("cycles_max")),
                num(cycles_to_us(tm.get("cycles"), tname, tm), D_US, cls="num derived"),
                num(cycles_to_us(tm.get("cycles_max"), tname, tm), D_US, cls="num derived"),
                num(est.get("cycles"), D_CYC, k("estimate", "cycles")) if est else txt("no estimate", "missing"),
                num(_pct_diff(est.get("cycles"), tm.get("cycles")), D_DIFF, cls="num derived"),
            ])
            mem.rows.append([
                txt(tname, "label"),
                num(tm.get("flash_bytes"), D_CYC, k("flash_bytes")),
                num(est.get("flash_bytes"), D_CYC, k("estimate", "flash_bytes")) if est else txt("no estimate", "missing"),
                num(_pct_diff(est.get("flash_bytes"), tm.get("flash_bytes")), D_DIFF, cls="num derived"),
                num(tm.get("ram_bytes"), D_CYC, k("ram_bytes")),
                num(est.get("ram_bytes"), D_CYC, k("estimate", "ram_bytes")) if est else txt("no estimate", "missing"),
                num(_pct_diff(est.get("ram_bytes"), tm.get("ram_bytes")), D_DIFF, cls="num derived"),
            ])
        lat.note = ("µs = cycles × clocks per cycle / clock (PIC18 counts instruction cycles of 4 clocks; AVR counts "
                    "clocks). Estimate: nnik's cost model, before compiling; difference = (estimate − measured) / measured.")
        sec.tables += [lat, mem]
        tc = Table("toolchain-table", "Toolchains", ["target", "compiler", "flags", "clock (Hz)"])
        for tname, tm in ran:
            tc.rows.append([txt(tname, "label"), txt(tm.get("compiler")), txt(tm.get("flags"), "mono"),
                            num(tm.get("clock_hz"), 0, _key("targets", tname, "clock_hz"))])
        if ran:
            sec.tables.append(tc)

        # cost vs accuracy
        hdr = ["target", "implementation", "cycles (mean)", "µs", "flash (bytes)", "RAM (bytes)"] + \
              [f"{o} max ({unit})" for o in self.outputs]
        ca = Table("cost-table", "Cost vs accuracy: the MLP against the float math.h IK and a lookup table", hdr)
        points: dict[str, list[dict]] = {}
        for tname, tm in ran:
            points[tname] = []
            for i in implementations(m, tname, tm):
                kp = i["keypath"]
                row = [txt(tname, "label"), txt(i["label"], f"impl-{i['kind']}"),
                       num(i["cycles"], D_CYC, _key(*kp, "cycles")),
                       num(cycles_to_us(i["cycles"], tname, tm), D_US, cls="num derived"),
                       num(i["flash"], D_CYC, _key(*kp, "flash_bytes")),
                       num(i["ram"], D_CYC, _key(*kp, "ram_bytes"))]
                for j in range(self.n_out):
                    v = _get(i["err"], j)
                    row.append(num(v, D_UNIT, f"{i['err_key']}/{j}" if i["err_key"] and v is not None else None))
                ca.rows.append(row)
                if _finite(i["cycles"]) and _worst(i["err"]) is not None and i["cycles"] > 0 and _worst(i["err"]) > 0:
                    points[tname].append(dict(label=i["label"], kind=i["kind"], cycles=float(i["cycles"]),
                                              err=_worst(i["err"])))
        for tname in target_names(m):
            tm, reason = target_status(m, tname)
            if tm is None:
                ca.rows.append([txt(tname, "label"), not_run_cell(reason, 5 + self.n_out)])
        ca.note = ("MLP error: the fixed-point model's delivered commands (bit-exact on the chip); baselines: as measured "
                   "by their own harness. Lower-left is better in the picture.")
        sec.tables.append(ca)
        wins, losses = lut_verdicts(m)
        for w in wins:
            sec.verdicts.append(("bad", w))
        for s in losses:
            sec.verdicts.append(("good", s))
        if ran and not wins and not losses:
            sec.not_run.append("LUT comparison not run: no target reports a `lut` baseline with cycles and max_abs")
        if any(points.values()):
            self._plot(sec, lambda: self.plot_cost(points))
        else:
            sec.not_run.append("cost vs accuracy picture not run: no target reports cycles together with errors")
        return sec

    def plot_cost(self, points) -> Fig:
        from nnik import report_plots as rp

        rp.cost_accuracy(self.out / PNG_COST, points=points, unit=self.unit,
                         title=f"{self.m['name']}: cycles per IK vs max error")
        return Fig(PNG_COST, "cost vs accuracy per target",
                   "Cycles per IK call against the worse output's max error, per target (log-log).")

    # ---- 6. training -----------------------------------------------------------------------------

    def training(self) -> Section:
        m = self.m
        sec = Section("training", "Training and export")
        t = Table("training-table", "Training", ["item", "value"])
        t.rows.append([txt("training time (s)", "key"), num(m.get("train_seconds"), D_SEC, "train_seconds")])
        hist = list(getattr(self.inp.model, "history", None) or [])
        if hist:
            restarts = sorted({int(h["restart"]) for h in hist})
            best = [h for h in hist if h.get("best")]
            t.rows.append([txt("restarts", "key"), num(len(restarts), 0, cls="num derived")])
            if best:
                t.rows.append([txt("best validation MSE (standardised)", "key"),
                               num(min(h["val"] for h in best), "sci", cls="num derived")])
        onnx = m.get("onnx")
        if isinstance(onnx, dict):
            t.rows.append([txt("ONNX vs torch, max |diff|", "key"), num(onnx.get("max_abs_diff"), "sci", "onnx/max_abs_diff")])
            t.rows.append([txt("ONNX tolerance", "key"), num(onnx.get("tolerance"), "sci", "onnx/tolerance")])
            ok = bool(onnx.get("ok"))
            t.rows.append([txt("ONNX check", "key"), Cell("passed" if ok else "FAILED", value=ok, key="onnx/ok",
                                                         cls="good" if ok else "bad")])
        else:
            t.rows.append([txt("ONNX check", "key"), Cell("not run — no `onnx` section in metrics.json", cls="notrun")])
        sec.tables.append(t)
        if self.inp.model is None:
            sec.not_run.append(f"training curve not run: {self.inp.model_reason}")
        elif not hist:
            sec.not_run.append(f"training curve not run: {MODEL_FILE} holds no training history")
        else:
            self._plot(sec, lambda: self.plot_training(hist))
        return sec

    def plot_training(self, hist) -> Fig:
        from nnik import report_plots as rp

        net = self.m.get("network") or {}
        rp.training_curve(self.out / PNG_TRAINING, history=hist,
                          title=f"{self.m['name']}: {'-'.join(map(str, net.get('shape', [])))} MLP, "
                                "Adam then L-BFGS (dot: switch)")
        return Fig(PNG_TRAINING, "training curve", "Train (dashed) and validation (solid) loss against wall-clock "
                   "time, per restart; the kept restart is thick, its best validation point starred.")

    # ---- 7. published references -------------------------------------------------------------------

    def references(self) -> Section:
        m = self.m
        sec = Section("references", "Published references beside this run")
        sec.paragraphs.append("Rows marked “published” are copied from the papers and were not measured here; "
                              "“this run” rows are this model's own measurements. Different chips, compilers and "
                              "networks: compare orders of magnitude, not digits.")
        t = Table("ref000-table", f"Seed 000 (CBA 2012), Table 1 — {PUB_000_SETUP}",
                  ["source", "method", "ROM words", "flash (bytes)", "time (ms)", "cycles"])
        for method, words, ms in PUB_000:
            t.rows.append([txt("published (seed 000)", "published"), txt(method), num(words, 0, cls="num published"),
                           num(words * 2, 0, cls="num derived published", title="2 bytes per PIC18 program word"),
                           num(ms, 1, cls="num published"),
                           num(ms * 1e-3 * PUB_000_MIPS, 0, cls="num derived published",
                               title="instruction cycles at 4 MIPS")])
        for tname in target_names(m):
            tm, reason = target_status(m, tname)
            if tm is None:
                t.rows.append([txt(f"this run, {tname}", "label"), not_run_cell(reason, 5)])
                continue
            clock = tm.get("clock_hz")
            src = f"this run, {tname}" + (f" @ {clock / 1e6:g} MHz" if _finite(clock) else "") + \
                  (f", {tm['compiler']}" if tm.get("compiler") else "")
            for i in implementations(m, tname, tm):
                kp = i["keypath"]
                us = cycles_to_us(i["cycles"], tname, tm)
                t.rows.append([txt(src, "label"), txt(i["label"]),
                               num(None if not _finite(i["flash"]) else i["flash"] / 2, 0, cls="num derived",
                                   title="flash bytes / 2"),
                               num(i["flash"], 0, _key(*kp, "flash_bytes")),
                               num(None if us is None else us / 1000, D_MS, cls="num derived"),
                               num(i["cycles"], 0, _key(*kp, "cycles"))])
        t.note = ("Published flash bytes (2 per ROM word) and cycles (time × 4 MIPS) are derived from the published "
                  "numbers; this run's ROM words are flash bytes / 2.")
        sec.tables.append(t)

        rel = _get(m, "float", "rel_pct")
        t4 = Table("ref004-table", "Seed 004 (UNICAMP), Table 1 — relative error, % (mean |error| / output span)",
                   ["source", "inputs", "q1 / output 1 (%)", "q2 / output 2 (%)", "x (%)", "y (%)"])
        for row, *vals in PUB_004:
            t4.rows.append([txt("published (seed 004)", "published"), txt(row)] +
                           [num(v, D_PCT, cls="num published") for v in vals])
        norm = _get(m, "network", "normalize")
        label = f"this run, {m['name']} ({', '.join(self.outputs)})"
        inputs_txt = "normalised to [-1, 1]" if norm else "raw mm (--no-normalize)"
        if isinstance(rel, list):
            t4.rows.append([txt(label, "label"), txt(inputs_txt)] +
                           [num(_get(rel, j), D_PCT, f"float/rel_pct/{j}") for j in range(2)] +
                           [txt("not measured", "missing"), txt("not measured", "missing")])
        else:
            t4.rows.append([txt(label, "label"), not_run_cell("no `float/rel_pct` in metrics.json", 5)])
        sib, sib_dir = self._sibling_metrics()
        if sib is not None:
            srel = _get(sib, "float", "rel_pct")
            snorm = _get(sib, "network", "normalize")
            t4.rows.append([txt(f"this run's sibling {sib_dir.name}", "label"),
                            txt("normalised to [-1, 1]" if snorm else "raw mm (--no-normalize)")] +
                           [num(_get(srel, j), D_PCT, cls="num derived") for j in range(2)] +
                           [txt("not measured", "missing"), txt("not measured", "missing")])
        else:
            other = "--no-normalize" if norm else "normalised"
            t4.rows.append([txt("the other normalisation", "label"),
                            not_run_cell(f"no {other} run of {m['name']} beside this one ({sib_dir})", 5)])
        if m["name"].startswith("hbot_unicamp"):
            cmp_note = "this run is that scenario, so the rows compare like with like (up to the fit)."
        else:
            cmp_note = f"this run is {m['name']}, so the rows show scale only, not a like-for-like comparison."
        t4.note = ("Seed 004 measured an HBOT with skewed axes (our hbot_unicamp); " + cmp_note +
                   " x, y errors need the forward model of the commands and are not measured by nnik.")
        sec.tables.append(t4)
        return sec

    def _sibling_metrics(self) -> tuple[dict | None, Path]:
        d = self.inp.model_dir.resolve()
        name = d.name
        other = d.parent / (name[: -len("-no-normalize")] if name.endswith("-no-normalize") else f"{name}-no-normalize")
        p = other / METRICS_FILE
        if p.is_file():
            try:
                sib = json.loads(p.read_text())
                if sib.get("name") == self.m.get("name"):
                    return sib, other
            except (json.JSONDecodeError, UnicodeDecodeError, AttributeError):
                pass
        return None, other

    # ---- 8. inputs -------------------------------------------------------------------------------

    def inputs(self) -> Section:
        sec = Section("inputs", "Inputs")
        t = Table("inputs-table", f"Files read from {self.inp.model_dir}", ["file", "present", "what"])
        for f, ok, note in self.inp.files:
            t.rows.append([txt(f, "mono"), Cell("yes" if ok else "no", cls="good" if ok else "notrun"), txt(note)])
        for k in ("fixed", "host", "tanh", "targets"):
            ok = k in self.m
            t.rows.append([txt(f"metrics.json `{k}`", "mono"), Cell("yes" if ok else "no", cls="good" if ok else "notrun"),
                           txt("present" if ok else f"not run: no `{k}` section in metrics.json")])
        sec.tables.append(t)
        return sec

    def summary(self) -> Section:
        sec = Section("summary", "Summary")
        t = Table("summary-table", "At a glance", list(SUMMARY_HEADER))
        for r in summary_rows(self.m):
            cls = "notrun" if r[1] == "not run" else ("bad" if r[1].startswith("NOT") or r[1] in ("FAILED", "wins") else "")
            t.rows.append([txt(r[0], "label"), txt(r[1], cls), txt(r[2])])
        sec.tables.append(t)
        return sec


def _truth(m: dict) -> str:
    t = _get(m, "dataset", "truth", default="truth")
    return "exact IK" if t == "analytic IK" else t


def _flatten(d: dict, prefix: str = "") -> list[tuple[str, str]]:
    out = []
    for k, v in d.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out += _flatten(v, f"{name}.")
        elif isinstance(v, (list, tuple)):
            out.append((name, ", ".join(map(str, v))))
        else:
            out.append((name, str(v)))
    return out


# ============================================================================================
# rendering
# ============================================================================================

_TICKS = re.compile(r"`([^`]+)`")


def _ticks_html(s: str):
    from markupsafe import Markup

    return Markup(_TICKS.sub(lambda mo: f"<code>{mo.group(1)}</code>", html.escape(str(s), quote=False)))


def render_html(sections: list[Section], metrics: dict) -> str:
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(TEMPLATE_DIR)),
                             autoescape=jinja2.select_autoescape(["html", "j2"]), trim_blocks=True, lstrip_blocks=True,
                             undefined=jinja2.StrictUndefined)
    env.filters["ticks"] = _ticks_html
    from nnik import __version__

    return env.get_template(TEMPLATE).render(
        sections=sections, m=metrics, version=__version__,
        generated=_dt.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z"),
    )


def _md_escape(s: str) -> str:
    return str(s).replace("|", "\\|").replace("\n", " ")


def render_markdown(sections: list[Section], metrics: dict) -> str:
    out = [f"# nnik report: {metrics['name']}", ""]
    for sec in sections:
        out += [f"## {sec.title}", ""]
        for p in sec.paragraphs:
            out += [p, ""]
        for cls, v in sec.verdicts:
            out += [f"> {'**' if cls == 'bad' else ''}{v}{'**' if cls == 'bad' else ''}", ""]
        for n in sec.not_run:
            out += [f"> *{n}*", ""]
        for t in sec.tables:
            out += [f"**{t.title}**", ""]
            out.append("| " + " | ".join(_md_escape(h) for h in t.header) + " |")
            out.append("|" + "|".join("---:" if r else "---" for r in _numeric_columns(t)) + "|")
            carry: dict[int, int] = {}
            for row in t.rows:
                cells, it = [], iter(row)
                col = 0
                while col < len(t.header):
                    if carry.get(col, 0) > 0:
                        carry[col] -= 1
                        cells.append("")
                        col += 1
                        continue
                    c = next(it, None)
                    if c is None:
                        cells.append("")
                        col += 1
                        continue
                    cells.append(_md_escape(c.text))
                    if c.rowspan > 1:
                        carry[col] = c.rowspan - 1
                    cells += [""] * (c.colspan - 1)
                    col += c.colspan
                out.append("| " + " | ".join(cells) + " |")
            if t.note:
                out += ["", f"*{t.note}*"]
            out.append("")
        for f in sec.figures:
            out += [f"![{f.alt}]({f.file})", "", f"*{f.caption}*", ""]
    return "\n".join(out).rstrip() + "\n"


def _numeric_columns(t: Table) -> list[bool]:
    """Per column: do most of its cells (in rows without spans) hold numbers?"""
    n = len(t.header)
    votes = [[0, 0] for _ in range(n)]
    for row in t.rows:
        if len(row) != n or any(c.colspan > 1 or c.rowspan > 1 for c in row):
            continue
        for i, c in enumerate(row):
            votes[i]["num" in c.cls.split()] += 1
    return [v[1] > v[0] for v in votes]


def build_sections(inp: Inputs, out_dir: Path) -> list[Section]:
    b = _Builder(inp, out_dir)
    return [b.summary(), b.scenario(), b.accuracy(), b.fixed(), b.tanh(), b.targets(), b.training(),
            b.references(), b.inputs()]


def write_report(model_dir: Path, out_dir: Path | None = None) -> Path:
    """Write OUT_DIR/index.html, report.md and the PNGs for MODEL_DIR; return the index.html path.

    Default OUT_DIR: MODEL_DIR/report. Raises NnikError if MODEL_DIR has no usable metrics.json.
    """
    model_dir = Path(model_dir)
    out_dir = Path(out_dir) if out_dir is not None else model_dir / REPORT_DIRNAME
    inp = load_inputs(model_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    for png in ALL_PNGS:  # no stale pictures from an earlier report
        (out_dir / png).unlink(missing_ok=True)
    sections = build_sections(inp, out_dir)
    index = out_dir / "index.html"
    index.write_text(render_html(sections, inp.metrics), encoding="utf-8")
    (out_dir / "report.md").write_text(render_markdown(sections, inp.metrics), encoding="utf-8")
    return index
