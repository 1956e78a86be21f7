"""The command line, one module per command or task group; nnik.cli builds the parser from their
``register(sub)`` and maps errors to the one `nnik: error:` line.

start here: run (also generate/train's shared arguments), job; the pick: select, search, verify,
report, export; the MLP alone: mlp_steps (generate, train, evaluate), estimate, tanh; measured
machines: synth_csv, shaper_calibrate. Shared: common_options (--quiet, --json, --seed, -o,
--target), option_types (checked values), model_dirs (OUTDIR and its checks)."""
