"""`nnik generate`, `nnik train`, `nnik evaluate`: the MLP family's stages one at a time, for
experiments on the network (`nnik run` runs them inside its pipeline)."""

from __future__ import annotations

from nnik import pipeline
from nnik.commands import common_options as co
from nnik.commands.model_dirs import add_model_dir, scenario_outdir, warn_training
from nnik.commands.run import add_scenario_args
from nnik.files.outdir import check_model_dir
from nnik.report.console import console, print_accuracy

STEP = " (one of the MLP's stages alone; `nnik run` runs every stage for every family)"


SCENARIO_STEPS = (  # name, help, description, what -o is, what --no-normalize does
    ("generate", "sample the scenario's workspace and label it with the exact IK (data.npz)",
     "Sample the scenario's workspace and label every point with the exact IK, or read a measured machine's marks; "
     "write OUTDIR/data.npz (the train, validation and test sets)",
     "the model directory data.npz is written to",
     "only where the data goes: build/<name>-no-normalize/, the directory of `nnik train --no-normalize` "
     "(default OUTDIR)"),
    ("train", "train the scenario's MLP on OUTDIR/data.npz (model.pt, model.onnx)",
     "Train the scenario's [network] MLP on OUTDIR/data.npz and write OUTDIR/model.pt and model.onnx",
     "the model directory that holds data.npz, where model.pt and model.onnx are written",
     "train on raw mm inputs, without input normalisation (seed 004's Table 1 'without'; default OUTDIR "
     "build/<name>-no-normalize/)"),
)


def register(sub) -> None:
    funcs = {"generate": cmd_generate, "train": cmd_train}
    for name, help_, description, outdir_what, no_normalize in SCENARIO_STEPS:
        p = co.add_command(sub, name, help_, description + STEP + ".")
        add_scenario_args(p, outdir_what, no_normalize)
        p.set_defaults(func=funcs[name])
    p = co.add_command(sub, "evaluate", "the trained MLP's accuracy against the exact IK (metrics.json)",
                       "Measure the trained MLP's float accuracy on the test set against the exact IK (and an affine "
                       "least-squares fit for scale), check model.onnx against torch, and write metrics.json"
                       + STEP + ".", result=True)
    add_model_dir(p)
    p.set_defaults(func=cmd_evaluate)


def cmd_generate(args) -> None:
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(args.scenario)
    out = scenario_outdir(args, scn, create=True)
    ds = pipeline.generate(scn, out)
    console.print(f"wrote {out / pipeline.DATA_FILE}: {', '.join(f'{len(v)} {k}' for k, v in ds.p.items())} points")


def cmd_train(args) -> None:
    from nnik.machine.scenario import load_scenario

    scn = load_scenario(args.scenario)
    out = scenario_outdir(args, scn)
    model = pipeline.train(scn, out, normalize=False if args.no_normalize else None, progress=co.show_progress(args))
    warn_training(model)
    console.print(f"wrote {out / pipeline.MODEL_FILE} and {out / pipeline.ONNX_FILE} ({model.train_seconds:.1f} s)")


def cmd_evaluate(args) -> dict:
    m = pipeline.evaluate(check_model_dir(args.model_dir))
    print_accuracy(m)
    return m
