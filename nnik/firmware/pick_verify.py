"""The verified pick's integer model, and `nnik verify` of the C on disk: the bytes in c/ (the pick)
or c/alt/<family>/ (a family's best) run as they are, on the host and on a simulated chip, against
the refitted implementation they were recorded for; results are recorded by :mod:`nnik.files.pick_state`
only when every run was bit-exact."""

from __future__ import annotations

import json
from pathlib import Path

from nnik.files import pick_state
from nnik.errors import NnikError
from nnik.files.pick_state import PickStatus, status

_REFIT: dict = {}


def refit(outdir: Path, family: str, config: dict, model_hash: str | None, source: str = "ladder",
          where: str = "the recorded selection's"):
    """The implementation behind a recorded row (the pick or a family's best), refitted, and
    checked to be the model that was recorded."""
    from nnik import pipeline
    from nnik.implementations import FAMILIES

    key = (str(Path(outdir).resolve()), family, json.dumps(config, sort_keys=True), model_hash)
    if key not in _REFIT:
        if family not in FAMILIES:
            raise NnikError(f"unknown implementation family {family!r} in the recorded selection", str(outdir))
        problem = pipeline.problem_for(Path(outdir))
        if source == "search":  # the search fits an MLP on its own small training budget
            from nnik.implementations.mlp.family import fast_problem

            problem = fast_problem(problem)
        try:
            impl = FAMILIES[family].fit(problem, config)
        except (NnikError, TypeError, ValueError, KeyError, IndexError, AttributeError) as exc:  # a hand-edited one
            why = str(exc) if isinstance(exc, NnikError) else f"{type(exc).__name__}: {str(exc)[:80]}"
            raise NnikError(f"{where} {family} configuration {json.dumps(config)[:80]} cannot be refitted ({why}); "
                            f"run `nnik select {outdir}`", str(outdir)) from None
        if model_hash is not None and impl.source_hash() != model_hash:
            raise NnikError(f"refitting the recorded {family} does not give the model that was verified; run "
                            f"`nnik select {outdir}`", str(outdir))
        _REFIT[key] = impl
    return _REFIT[key]


def pick_implementation(outdir: Path, st: PickStatus | None = None):
    """The verified pick's integer model (``st`` must be ok)."""
    st = st or status(outdir)
    if not st.ok:
        raise NnikError(st.message, str(outdir))
    m = st.marker
    return refit(outdir, m["family"], m["config"], m["model_hash"], m.get("source", "ladder"), "pick.json's")


def verify_files(impl, c_dir: Path, target: str, work: Path) -> dict:
    """Run c_dir/NAME.{c,h} as they are on disk: on the host, and on ``target``'s simulator (fast
    path, and the portable path where the family checks it) unless ``target`` is "host"."""
    from nnik.implementations.verify import verify_host, verify_on_target

    res = {"host": verify_host(impl, c_dir, write=False)}
    if target != "host":
        res[target] = verify_on_target(impl, target, c_dir, work / target, write=False)
        if target in impl.portable_checked_on:
            res[f"{target}_portable"] = verify_on_target(impl, target, c_dir, work / f"{target}_portable",
                                                         portable=True, n_inside=60, write=False)
    return res


def verify_pick(outdir: Path, target: str) -> tuple[PickStatus, dict]:
    """`nnik verify OUTDIR`: run c/NAME.c as it is on disk against the pick's integer model; the
    results are recorded for these bytes when every run was bit-exact (see pick_state.record)."""
    outdir = Path(outdir)
    st = status(outdir)
    if st.state in ("none", "corrupt", "other_model", "missing"):
        raise NnikError(st.message, str(outdir))
    impl = refit(outdir, st.marker["family"], st.marker["config"], st.marker["model_hash"],
                 st.marker.get("source", "ladder"))
    res = verify_files(impl, outdir / "c", target, (outdir / "targets" / "pick").resolve())
    pick_state.record(outdir, st.marker, res)
    return status(outdir), res


def verify_family(outdir: Path, family: str, target: str) -> tuple[dict, dict]:
    """`nnik verify OUTDIR --family F`: run c/alt/F/NAME.c as it is on disk against the family's
    recorded best; when every run was bit-exact, its row in metrics.json's selection holds these
    results (and only the figures measured on these bytes)."""
    from nnik import pipeline
    from nnik.files.c_hash import dir_hash

    outdir = Path(outdir)
    m = pipeline.load_metrics(outdir)
    sel = m.get("selection") if isinstance(m.get("selection"), dict) else {}
    row = next((r for r in sel.get("implementations", []) if r.get("family") == family and "config" in r
                and not r.get("skipped")), None)
    if row is None:
        raise NnikError(f"no {family} implementation in metrics.json's selection; run `nnik select {outdir}`",
                        str(outdir))
    c_dir = outdir / "c" / "alt" / family
    if dir_hash(c_dir, m["name"]) is None:
        raise NnikError(f"c/alt/{family}/{m['name']}.c or its header is missing; run `nnik select {outdir}`",
                        str(outdir))
    impl = refit(outdir, family, row["config"], row.get("model_hash"), sel.get("source", "ladder"))
    res = verify_files(impl, c_dir, target, (outdir / "targets" / "verify" / family).resolve())
    ran = {k: r for k, r in res.items() if "not_run" not in r}
    if ran and all(r["bit_exact"] for r in ran.values()):
        h = ran["host"]["c_hash"]
        if h != row.get("c_hash"):  # other bytes: the figures measured on the old ones go
            again = f"the C changed since; run `nnik verify {outdir} --family {family} --target CHIP`"
            row["targets"] = {k: {"not_run": again.replace("CHIP", k.split("_")[0])} for k in row.get("targets") or {}}
            row["cycles"], row["flash_bytes"], row["c_hash"] = {}, {}, h
        row["host"] = ran["host"]
        for k, r in ran.items():
            if k != "host":
                row.setdefault("targets", {})[k] = r
                if "_" not in k:
                    row.setdefault("cycles", {})[k] = r["cycles"]
                    row.setdefault("flash_bytes", {})[k] = r["flash_bytes"]
        pipeline.write_metrics(outdir, {"selection": sel, "implementations": sel["implementations"]})
    return row, res
