"""`nnik search`: seeded proposals, constraints from [target], a journal study that survives a
SIGKILL, bad storage and a study of another scenario (one line, exit 2), and two workers sharing a
study on a real PostgreSQL server."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

optuna = pytest.importorskip("optuna")

from nnik.search import study as search  # noqa: E402
from nnik.cli import main  # noqa: E402
from nnik.search.storage import JOURNAL_FILE, open_storage, open_study  # noqa: E402
from optuna.trial import TrialState  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
FINISHED = (TrialState.COMPLETE, TrialState.PRUNED, TrialState.FAIL)


def _copy_run(src: Path, dst: Path) -> Path:
    """A fresh output directory holding the trained run (another machine's copy of it)."""
    dst.mkdir(parents=True)
    for f in ("data.npz", "model.pt", "model.onnx", "metrics.json"):
        shutil.copy2(src / f, dst / f)
    return dst


def _study(out: Path, url: str | None = None):
    scn = search.pipeline.load_pair(out)[0].scenario
    return open_study(open_storage(url, out), search.study_name(scn), scn.fingerprint, scn.name,
                      list(search.DIRECTIONS), create=False)


def _cli(*args, **kw) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen([sys.executable, "-m", "nnik", "search", *map(str, args)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def _one_line_error(capsys, rc, *needles):
    err = capsys.readouterr().err
    assert rc == 2, err
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("nnik: warning")]
    assert len(lines) == 1 and lines[0].startswith("nnik: error: "), err
    for n in needles:
        assert n in lines[0], lines[0]
    assert "Traceback" not in err


@pytest.fixture(scope="module")
def lut_study(galvo_run, tmp_path_factory) -> Path:
    """A 6-trial LUT-only search of galvo_cba2012 (trials only)."""
    out = _copy_run(galvo_run, tmp_path_factory.mktemp("search") / "a")
    search.run_worker(str(out), None, search.study_name(search.pipeline.load_pair(out)[0].scenario), 6, ["lut"])
    return out


def _proposals(out: Path) -> list[dict]:
    return [t.params for t in sorted(_study(out).get_trials(states=FINISHED), key=lambda t: t.number)]


def test_seeded_proposals_repeat(lut_study, galvo_run, tmp_path, monkeypatch):
    again = _copy_run(galvo_run, tmp_path / "b")
    search.run_worker(str(again), None, "nnik-galvo_cba2012", 6, ["lut"])
    first = _proposals(lut_study)
    assert len(first) == 6
    assert _proposals(again) == first
    monkeypatch.setattr(search, "SEED", search.SEED + 1)
    other = _copy_run(galvo_run, tmp_path / "c")
    search.run_worker(str(other), None, "nnik-galvo_cba2012", 6, ["lut"])
    assert _proposals(other) != first


def test_constraints_follow_target(lut_study):
    study = _study(lut_study)
    target = search.pipeline.load_pair(lut_study)[0].scenario.target
    done = study.get_trials(states=(TrialState.COMPLETE,))
    assert done
    for t in done:
        con = {k.split(":", 1)[1]: v for k, v in t.system_attrs.items() if k.startswith("constraints:")}
        assert con["max_error"] == pytest.approx(t.values[0] - target["max_error"])
        assert search.feasible(t.user_attrs, target) == (t.values[0] <= target["max_error"])
    # optional limits become constraints too; a trial over max_cycles is infeasible
    t = min(done, key=lambda t: t.values[1])
    tight = {**target, "max_error": 1e9, "max_cycles": t.values[1] - 1, "max_flash_bytes": 10**9}
    assert set(search.constraint_values(t.user_attrs, tight)) == {"max_error", "max_cycles", "max_flash_bytes"}
    assert not search.feasible(t.user_attrs, tight)
    assert search.feasible(t.user_attrs, {**tight, "max_cycles": t.values[1]})
    assert not search.feasible({}, {**tight, "max_cycles": None})  # a config that could not be built
    front = search.front_trials(study, target)
    assert front and all(not search._dominates(o.values, f.values) for f in front for o in done)
    ok = search.front_trials(study, {**target, "max_error": t.values[0]}, feasible_only=True)
    assert ok and all(f.values[0] <= t.values[0] for f in ok)


def test_show_prints_front_without_running(lut_study, capsys):
    before = len(_study(lut_study).get_trials())
    assert main(["search", str(lut_study), "--show"]) == 0
    out = capsys.readouterr().out
    assert "Pareto front" in out and "lut" in out
    assert len(_study(lut_study).get_trials()) == before


def test_journal_resumes_after_sigkill(galvo_run, tmp_path):
    out = _copy_run(galvo_run, tmp_path / "k")
    proc = _cli(out, "--trials", 20, "--worker", "--families", "lut")
    done_before: dict[int, tuple] = {}
    deadline = time.monotonic() + 300
    while time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
        if (out / JOURNAL_FILE).is_file():
            try:
                trials = _study(out).get_trials(states=(TrialState.COMPLETE, TrialState.PRUNED))
            except Exception:
                continue
            if len(trials) >= 2:
                done_before = {t.number: (t.params, t.values) for t in trials}
                break
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert 2 <= len(done_before) < 20
    res = _cli(out, "--trials", 20, "--worker", "--families", "lut")
    _, err = res.communicate(timeout=300)
    assert res.returncode == 0, err
    trials = _study(out).get_trials()
    finished = [t for t in trials if t.state in (TrialState.COMPLETE, TrialState.PRUNED)]
    assert len(finished) == 20
    assert len({t.number for t in trials}) == len(trials)
    for n, (params, values) in done_before.items():  # nothing completed before the kill was lost
        t = next(t for t in trials if t.number == n)
        assert (t.params, t.values) == (params, values)
    # a new study starts from the family's ladder best (what `nnik run` picks from), then the rest
    # of its ladder in the ladder's order (the warm start)
    problem = search.pipeline.problem_for(out)
    best = search.ladder_bests(problem, ["lut"])[0][1]
    order = [best] + [c for c in search.FAMILIES["lut"].ladder(problem) if c != best]
    firsts = [t for t in finished if t.number < len(order)]
    assert len(firsts) >= len(order) - 1  # the killed trial may have been one of them
    assert all(t.user_attrs["config"] == {**order[t.number], "k": list(order[t.number]["k"])} for t in firsts)


def test_bad_storage_is_one_line(lut_study, capsys):
    rc = main(["search", str(lut_study), "--trials", "1", "--worker", "--storage", "mongodb://x/y"])
    _one_line_error(capsys, rc, "--storage", "mongodb")
    rc = main(["search", str(lut_study), "--trials", "1", "--worker", "--storage", "postgresql://nnik:secret@127.0.0.1:1/x"])
    _one_line_error(capsys, rc, "--storage")
    assert "secret" not in capsys.readouterr().err


def test_study_of_another_scenario_is_refused(galvo_run, tmp_path, capsys):
    out = _copy_run(galvo_run, tmp_path / "w")
    open_study(open_storage(None, out), "shared", "0123456789abcdef", "corexy_nonlinear", list(search.DIRECTIONS))
    rc = main(["search", str(out), "--trials", "1", "--worker", "--study", "shared"])
    _one_line_error(capsys, rc, "corexy_nonlinear", "--study")
    rc = main(["search", str(out), "--show", "--study", "missing"])
    _one_line_error(capsys, rc, "no study 'missing'")


# ---- PostgreSQL: two workers, one study -------------------------------------------------------------
PG_BIN = Path("/usr/lib/postgresql/15/bin")


def _pg_tool(name: str) -> str:
    p = shutil.which(name) or (str(PG_BIN / name) if (PG_BIN / name).is_file() else None)
    if p is None:
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(f"{name} not found but NNIK_REQUIRE_TOOLCHAINS=1")
        pytest.skip(f"{name} not installed (apt-get install postgresql)")
    return p


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def postgres():
    """A private PostgreSQL server on a free port (run as `nobody` when the tests run as root, in a
    temporary directory of its own that `nobody` can reach)."""
    initdb, pg_ctl = _pg_tool("initdb"), _pg_tool("pg_ctl")
    base = Path(tempfile.mkdtemp(prefix="nnik-pg-"))
    as_user = []
    if os.geteuid() == 0:
        shutil.chown(base, "nobody")
        base.chmod(0o700)
        as_user = ["runuser", "-u", "nobody", "--"]
    data, port = base / "data", _free_port()
    subprocess.run([*as_user, initdb, "-D", str(data), "-U", "nnik", "-A", "trust", "--no-sync", "-E", "UTF8"],
                   check=True, capture_output=True)
    subprocess.run([*as_user, pg_ctl, "-D", str(data), "-l", str(base / "log"), "-w", "-o",
                    f"-p {port} -k {base} -c listen_addresses=127.0.0.1 -c fsync=off", "start"],
                   check=True, capture_output=True)
    try:
        yield f"postgresql://nnik@127.0.0.1:{port}/postgres"
    finally:
        subprocess.run([*as_user, pg_ctl, "-D", str(data), "-m", "immediate", "-w", "stop"], capture_output=True)
        shutil.rmtree(base, ignore_errors=True)


def test_two_workers_share_a_postgres_study(galvo_run, tmp_path, postgres):
    a, b = _copy_run(galvo_run, tmp_path / "ma"), _copy_run(galvo_run, tmp_path / "mb")  # two machines
    n = 10
    procs = [_cli(d, "--trials", n, "--worker", "--families", "lut", "--storage", postgres) for d in (a, b)]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
    trials = [t for t in _study(a, postgres).get_trials() if t.state != TrialState.WAITING]  # ladder queue left
    assert all(t.state in FINISHED for t in trials)  # none left running: none lost
    assert n <= len(trials) <= n + 1  # the other worker may finish the trial it had begun
    assert len({t.number for t in trials}) == len(trials) == len({t._trial_id for t in trials})
    workers = {t.user_attrs["worker"] for t in trials}
    assert len(workers) == 2, workers  # both workers' trials are in the study
    assert not (a / JOURNAL_FILE).exists() and not (b / JOURNAL_FILE).exists()


def test_search_verifies_the_front_and_picks(galvo_run, tmp_path, capsys):
    out = _copy_run(galvo_run, tmp_path / "p")
    assert main(["search", str(out), "--trials", "6", "--families", "poly", "--no-warm-start"]) == 0, \
        capsys.readouterr().err
    m = search.pipeline.load_metrics(out)
    s, sel = m["search"], m["selection"]
    tg = sel["target"]
    assert sel["source"] == "search" and s["storage"] == "journal" and s["study"] == "nnik-galvo_cba2012"
    assert s["trials"]["complete"] + s["trials"]["pruned"] == 6
    front = s["front"]
    assert front and s["feasible_front"] >= 1
    assert all(r["meets_target"] == (r["pre_max"] <= tg["max_error"]) for r in front)
    pts = [(r["pre_max"], r["cycles"], r["flash_bytes"]) for r in front]
    assert not any(search._dominates(a, b) for a in pts for b in pts)
    (row,) = [r for r in sel["implementations"] if r["picked"]]
    # the rule of selection.choose: the cheapest on the chip, verified bit-exact on host and both chips
    assert row["estimate"][tg["chip"]]["cycles"] == pytest.approx(min(r["cycles"] for r in front if r["meets_target"]))
    assert row["host"]["bit_exact"] and all(row["targets"][t]["bit_exact"] for t in ("avr", "pic18"))
    assert row["pre_max"] <= tg["max_error"]
    assert (out / "c" / "galvo_cba2012.c").is_file() and sel["pick"]["model_hash"] == row["model_hash"]
    assert len(sel["ladder"]) >= len(front)  # the report's picture shows the front


def test_a_short_search_is_never_worse_than_the_ladder(galvo_run, tmp_path, capsys):
    """Issue 15: the warm start queues each family's ladder best first, so even two trials see what
    `nnik run` would pick from."""
    from nnik import selection as sel

    out = _copy_run(galvo_run, tmp_path / "short")
    assert main(["search", str(out), "--trials", "2", "--families", "lut,poly"]) == 0, capsys.readouterr().err
    m = search.pipeline.load_metrics(out)
    tg = m["selection"]["target"]
    (row,) = [r for r in m["selection"]["implementations"] if r["picked"]]
    problem = search.pipeline.problem_for(out)
    bests = sel.family_bests(sel.fit_ladder(problem, ["lut", "poly"], max_error=tg["max_error"]), tg)
    ladder_cycles = min(c.est[tg["chip"]]["cycles"] for c in bests.values() if c.meets(tg["max_error"]))
    assert row["pre_max"] <= tg["max_error"]
    assert row["estimate"][tg["chip"]]["cycles"] <= ladder_cycles + 1e-9


def test_warm_start_reuses_a_finished_ladder(galvo_run, tmp_path):
    """Issue 17: after a ladder selection (`nnik run`, `nnik select`) the warm start queues the
    family bests it recorded, without fitting the ladder again, when its key holds: the same
    data.npz and model.pt, the same [target] limits, and each family's C in c/alt/ still the C it
    verified. Any change of the key fits the ladder again."""
    from nnik import pipeline
    from nnik import selection as sel

    out = _copy_run(galvo_run, tmp_path / "warm")
    section = pipeline.select(out, progress=False, families=["lut", "poly"])
    problem = pipeline.problem_for(out)
    tg = problem.scn.target
    stored = pipeline.stored_bests(out, tg, ["lut", "poly"])
    assert stored == [(r["family"], r["config"]) for r in section["implementations"]]
    assert stored == search.ladder_bests(problem, ["lut", "poly"])  # what fitting the ladder again gives
    fitted = []

    def tracer(frame, event, arg):
        if frame.f_code is sel.fit_ladder.__code__:
            fitted.append(frame.f_locals.get("families"))

    study = optuna.create_study(directions=list(search.DIRECTIONS))
    before = sys.gettrace()
    sys.settrace(tracer)
    try:
        search.warm(study, out, ["lut", "poly"])
    finally:
        sys.settrace(before)
    assert fitted == []
    firsts = [t.system_attrs["fixed_params"] for t in study.get_trials(deepcopy=False)[:2]]  # queued, not run
    assert firsts == [search.params_of(fam, cfg) for fam, cfg in stored]
    # the key: another max_error, a family the selection did not fit, or other C in c/alt/
    assert pipeline.stored_bests(out, {**tg, "max_error": tg["max_error"] * 2}, ["lut", "poly"]) is None
    assert pipeline.stored_bests(out, tg, ["lut", "poly", "hybrid"]) is None
    c_file = out / "c" / "alt" / "lut" / "galvo_cba2012.c"
    c_file.write_text(c_file.read_text() + "/* edited */\n")
    assert pipeline.stored_bests(out, tg, ["lut", "poly"]) is None
    before = sys.gettrace()
    sys.settrace(tracer)
    try:
        search.warm(optuna.create_study(directions=list(search.DIRECTIONS)), out, ["lut", "poly"])
    finally:
        sys.settrace(before)
    assert fitted == [["lut", "poly"]]


def test_search_of_a_new_scenario_fits_the_ladder_once(tmp_path, capsys):
    """Issue 17: `nnik search SCENARIO` on an empty OUTDIR runs the pipeline's own data and ladder
    stage (the mlp trains there, as its family's fit: model.pt) and hands the family bests to the
    warm start, which does not fit the ladder again."""
    from nnik import selection as sel
    from nnik.implementations.mlp.train import train_model
    from tests.bad_input import with_training
    from tests.conftest import DATASETS, write_toml

    text = (DATASETS / "galvo_cba2012.toml").read_text()
    text = text.replace("n_train = 1000", "n_train = 300").replace("n_test = 20000", "n_test = 2000")
    text = with_training(text, "[training]\nrestarts = 1\nadam_steps = 500\n")
    out = tmp_path / "out"
    calls = []

    def tracer(frame, event, arg):
        if frame.f_code in (sel.fit_ladder.__code__, train_model.__code__):
            calls.append((frame.f_code.co_name, frame.f_locals.get("families")))

    before = sys.gettrace()
    sys.settrace(tracer)
    try:
        rc = main(["search", str(write_toml(tmp_path, text)), "-o", str(out), "--trials", "2", "--families", "lut"])
    finally:
        sys.settrace(before)
    assert rc == 0, capsys.readouterr().err
    assert calls == [("fit_ladder", ["mlp", "lut"]), ("train_model", None)]
    m = search.pipeline.load_metrics(out)
    assert (out / "model.pt").is_file() and m["selection"]["source"] == "search"
    lut_best = search.ladder_bests(search.pipeline.problem_for(out), ["lut"])[0][1]
    first = min(_study(out).get_trials(deepcopy=False), key=lambda t: t.number)
    assert first.user_attrs["config"] == {**lut_best, "k": list(lut_best["k"])}  # the warm start's first trial
