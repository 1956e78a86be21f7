"""`nnik verify MODEL_DIR`: the C on disk run again and compared bit for bit with its integer model."""

from __future__ import annotations

from nnik import pipeline
from nnik.commands import common_options as co
from nnik.commands.model_dirs import add_model_dir, evaluated_dir
from nnik.errors import NnikError
from nnik.report.console import console, print_accuracy

HELP = ("run the C on disk (the pick by default) and compare it bit for bit with its integer model, on the host and "
        "on --target's simulated chip")
DESCRIPTION = (
    "Compile the C as it is on disk and compare its outputs bit for bit with its integer model: the pick c/NAME.c "
    "(by default; it then says whether the pick is deliverable), a family's best in c/alt/FAMILY/ (--family), or "
    "the MLP's C in c/mlp/ and the float IK as `nnik export` wrote them (--mlp-pipeline). The host always runs "
    "(gcc with sanitizers); --target avr or pic18 runs it on the simulated chip too (simavr, gpsim) and reports "
    "cycles and flash. Exit 2 on any mismatch.")


def register(sub) -> None:
    p = co.add_command(sub, "verify", HELP, DESCRIPTION, result=True)
    add_model_dir(p)
    co.add_target(p, "host, or a simulated chip: avr (simavr) or pic18 (gpsim); the host runs too (default host)",
                  choices=("host", *co.CHIPS), default="host")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--family", choices=co.FAMILIES,
                      help="the family's best in c/alt/FAMILY/ instead of the pick in c/NAME.c")
    what.add_argument("--mlp-pipeline", action="store_true",
                      help="the scenario's MLP in c/mlp/ (both kernels) and the float IK, as `nnik export` wrote them")
    p.set_defaults(func=cmd_verify)


def cmd_verify(args) -> dict:
    """The pick (c/NAME.c as it is on disk) by default, a family's best (c/alt/F/) with --family,
    the MLP pipeline's kernels and the float IK (c/mlp/, what `nnik export` wrote) with
    --mlp-pipeline; always on the host, and on --target's simulator."""
    out = evaluated_dir(args.model_dir)
    if args.mlp_pipeline:
        res = pipeline.verify(out, args.target)
        print_accuracy(pipeline.load_metrics(out))
        if not res.get("bit_exact", False):
            raise NnikError(f"{args.target}: {res.get('mismatches')} mismatches between the C and the integer model")
        return res
    from nnik.firmware import pick_verify

    name = pipeline.load_metrics(out)["name"]
    if args.family:
        _, res = pick_verify.verify_family(out, args.family, args.target)
        what, st = f"c/alt/{args.family}/{name}.c", None
    else:
        st, res = pick_verify.verify_pick(out, args.target)
        what = st.file
    for k, r in res.items():
        if "not_run" in r:
            console.print(f"{what}: {k}: not run ({r['not_run']})")
        elif "cycles" in r:
            console.print(f"{what} ({r['c_hash']}): {k}: {r['cycles']:.0f} cycles, {r['flash_bytes']} B flash, "
                          f"{r['mismatches']} mismatches on {r['points']} vectors ({r['path']} path)")
        else:
            console.print(f"{what} ({r['c_hash']}): {k}: {r['mismatches']} mismatches on {r['points']} points")
    bad = {k: r for k, r in res.items() if "not_run" not in r and not r["bit_exact"]}
    if bad:
        again = f"; `nnik select {out}` writes the verified pick again" if st is not None else ""
        raise NnikError(f"{what} as it is on disk differs from its integer model: "
                        + ", ".join(f"{r['mismatches']} mismatches on {k}" for k, r in bad.items()) + again, str(out))
    if args.target != "host" and "not_run" in res.get(args.target, {}):
        raise NnikError(f"{args.target}: not run ({res[args.target]['not_run']})", str(out))
    if st is not None:
        console.print(st.message if st.ok else f"not yet deliverable: {st.message}")
    return {"file": what, "results": res, **({"deliverable": st.ok, "message": st.message} if st is not None else {})}
