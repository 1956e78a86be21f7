"""What metrics.json says about each target: its status, the implementations measured on it,
and whether a table (the lut family's best) beats the MLP."""

from __future__ import annotations

from nnik.report.document import D_CYC, D_UNIT, finite, fmt, keypath, lookup

# The targets a user expects to see, even when they were not run; others in metrics.json follow.
EXPECTED_TARGETS = ("avr", "pic18")


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
    if not (finite(cycles) and finite(clock) and clock > 0):
        return None
    return float(cycles) * clocks_per_cycle(t, tm) / float(clock) * 1e6


def pct_diff(est, meas) -> float | None:
    if not (finite(est) and finite(meas)) or meas == 0:
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
    """Every measured implementation on a target: the nnik MLP, MLP kernels, float IK and the lut
    family's best (what a firmware engineer would write: a table), as verified by the selection.

    Each: label, kind, keypath (tuple into metrics), cycles, flash, ram, err (list or None),
    err_key (metrics key prefix of err, or None).
    """
    out = []
    err, err_key = mlp_error(metrics)
    variant = lookup(metrics, "fixed", "tanh_variant") or lookup(metrics, "tanh", "variant")
    out.append(dict(label="nnik MLP" + (f" ({variant} tanh)" if variant else ""), kind="mlp",
                    keypath=("targets", t), cycles=tm.get("cycles"), flash=tm.get("flash_bytes"),
                    ram=tm.get("ram_bytes"), err=err, err_key=err_key))
    for name, k in (tm.get("kernels") or {}).items():
        if isinstance(k, dict):
            out.append(dict(label=f"MLP kernel {name}", kind="kernel", keypath=("targets", t, "kernels", name),
                            cycles=k.get("cycles"), flash=k.get("flash_bytes"), ram=k.get("ram_bytes"),
                            err=k.get("max_abs"), err_key=keypath("targets", t, "kernels", name, "max_abs")))
    b = lookup(tm, "baselines", "float")
    if isinstance(b, dict):
        out.append(dict(label="float IK with math.h", kind="float", keypath=("targets", t, "baselines", "float"),
                        cycles=b.get("cycles"), flash=b.get("flash_bytes"), ram=b.get("ram_bytes"),
                        err=b.get("max_abs"), err_key=keypath("targets", t, "baselines", "float", "max_abs")))
    rows = metrics.get("implementations")
    k = next((k for k, r in enumerate(rows) if isinstance(r, dict) and r.get("family") == "lut"
              and isinstance(lookup(r, "targets", t), dict)), None) if isinstance(rows, list) else None
    if k is not None:
        r, rt = rows[k], rows[k]["targets"][t]
        out.append(dict(label=f"lut family best ({r.get('describe', 'lut')})", kind="lut",
                        keypath=("implementations", k, "targets", t), cycles=rt.get("cycles"),
                        flash=rt.get("flash_bytes"), ram=rt.get("ram_bytes"), err=r.get("delivered_max_abs"),
                        err_key=keypath("implementations", k, "delivered_max_abs"), picked=r.get("picked") is True))
    return out


def worst(err) -> float | None:
    if not isinstance(err, (list, tuple)) or not err or not all(finite(e) for e in err):
        return None
    return float(max(err))


def lut_picked(metrics: dict) -> bool:
    """The lut family's best is the pick (selection's row marked picked)."""
    rows = metrics.get("implementations")
    return isinstance(rows, list) and any(isinstance(r, dict) and r.get("family") == "lut" and r.get("picked") is True
                                          for r in rows)


def _pick_file(metrics: dict) -> str:
    name = lookup(metrics, "selection", "pick", "file")
    return f"c/{name}" if isinstance(name, str) else "c/NAME.c"


def lut_verdicts(metrics: dict) -> tuple[list[str], list[str]]:
    """(sentences where the lut family's best wins, sentences where it was compared and does not)."""
    unit = metrics.get("unit", "")
    wins, losses = [], []
    for t in target_names(metrics):
        tm, _ = target_status(metrics, t)
        if tm is None:
            continue
        impls = implementations(metrics, t, tm)
        lut = next((i for i in impls if i["kind"] == "lut"), None)
        if lut is None or not finite(lut["cycles"]) or worst(lut["err"]) is None:
            continue
        le = worst(lut["err"])
        beaten = []
        for i in impls:
            if i["kind"] not in ("mlp", "kernel") or not finite(i["cycles"]) or worst(i["err"]) is None:
                continue
            if float(lut["cycles"]) < float(i["cycles"]) and le < worst(i["err"]):
                beaten.append(i)
        if beaten:
            for i in beaten:
                wins.append(
                    f"On {t} the lut family's best wins over the {i['label']}: fewer cycles "
                    f"({fmt(lut['cycles'], D_CYC)} vs {fmt(i['cycles'], D_CYC)}) and lower max error "
                    f"({fmt(le, D_UNIT)} vs {fmt(worst(i['err']), D_UNIT)} {unit}), at "
                    f"{fmt(lut['flash'], D_CYC)} vs {fmt(i['flash'], D_CYC)} bytes of flash. "
                    + (f"The table is this machine's pick ({_pick_file(metrics)})." if lut["picked"]
                       else "On this machine, consider flashing the table instead.")
                )
        else:
            losses.append(f"On {t} the lut family's best ({fmt(lut['cycles'], D_CYC)} cycles, max error "
                          f"{fmt(le, D_UNIT)} {unit}) is not both faster and more accurate than any MLP variant.")
    return wins, losses
