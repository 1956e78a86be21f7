"""`nnik search`'s Pareto front verified on the simulators: `nnik search SCENARIO.toml -o OUTDIR` end
to end, the front rows' measured figures belong to the C on disk (rerun, they come out the same), the
report leads with the front, a changed C hides its figures, and `nnik run --search N`."""

from __future__ import annotations

import copy
import json
import re
import shutil

import pytest

pytest.importorskip("optuna")

from nnik import pipeline  # noqa: E402

from nnik.search import front as search_front
from nnik.files.c_hash import dir_hash  # noqa: E402
from nnik.cli import main  # noqa: E402
from nnik.implementations import FAMILIES  # noqa: E402
from nnik.implementations.verify import verify_on_target  # noqa: E402
from nnik.report import write_report  # noqa: E402
from tests.bad_input import with_training
from tests.conftest import DATASETS, require_tool, write_toml  # noqa: E402
from tests.report.test_report import check_numbers, parse  # noqa: E402
from tests.search.test_search import _copy_run  # noqa: E402

NAME = "galvo_cba2012"
CHIPS = ("avr", "pic18")


@pytest.fixture(scope="module")
def searched(galvo_run, tmp_path_factory):
    """`nnik search datasets/galvo_cba2012.toml -o OUTDIR` (OUTDIR holding the trained run, so the
    command does not train again): lut and poly, 36 trials (the ladders first)."""
    require_tool("simavr")
    require_tool("gpsim")
    out = _copy_run(galvo_run, tmp_path_factory.mktemp("front") / "s")
    rc = main(["search", str(DATASETS / f"{NAME}.toml"), "-o", str(out), "--trials", "36", "--families", "lut,poly"])
    assert rc == 0
    return out, pipeline.load_metrics(out)


def _verified(m: dict) -> list[dict]:
    return [r for r in m["search"]["front"] if r.get("measured")]


def test_search_command_verifies_the_front_and_exports_the_pick(searched, capsys):
    out, m = searched
    s, sel = m["search"], m["selection"]
    tg = sel["target"]
    front, info = s["front"], s["front_verified"]
    meeting = [r for r in front if r["pre_max"] <= tg["max_error"]]
    assert meeting and info["meeting_max_error"] == len(meeting)
    assert info["cap"] == search_front.MAX_VERIFY and info["verified"] == min(len(meeting), info["cap"])
    for r in front:  # cheapest first: the cap keeps the cheapest points that meet max_error
        assert bool(r.get("measured")) == (r in meeting[:info["cap"]]), (r["trial"], r.get("not_verified"))
        if not r.get("measured"):
            assert "estimate only" in r["not_verified"] and set(r["estimate"]) == set(CHIPS)
    for r in _verified(m):
        assert r["bit_exact"] is True and r["checks"]["host"]["bit_exact"] and r["checks"]["host"]["points"] > 10_000
        for chip in CHIPS:
            ck = r["checks"][chip]
            assert ck["bit_exact"] and ck["mismatches"] == 0 and ck["path"] == "fast"
            assert r["measured"][chip] == {"cycles": ck["cycles"], "flash_bytes": ck["flash_bytes"]}
            assert ck["model_hash"] == r["model_hash"]
    # the pick: c/NAME.c is the picked family's best, which is the front row marked picked
    (pick,) = [r for r in sel["implementations"] if r["picked"]]
    (row,) = [r for r in front if r["picked"]]
    assert (row["family"], row["model_hash"]) == (pick["family"], pick["model_hash"]) == \
        (sel["pick"]["family"], sel["pick"]["model_hash"])
    assert row["c_dir"] == f"c/alt/{pick['family']}" and row["c_hash"] == pick["c_hash"]
    assert dir_hash(out / "c", NAME) == pick["c_hash"]
    assert (out / "c" / f"{NAME}.c").read_text() == (out / row["c_dir"] / f"{NAME}.c").read_text()
    assert row["measured"][tg["chip"]]["cycles"] == pick["cycles"][tg["chip"]]
    # --show prints the study's front without running anything
    capsys.readouterr()
    assert main(["search", str(out), "--show"]) == 0
    shown = capsys.readouterr().out
    assert f"{sum(r['meets_target'] for r in front)} of {len(front)} points meet" in shown
    assert all(f in shown for f in {r["family"] for r in front})


def test_front_measurements_belong_to_the_c_on_disk(searched):
    """A made-up figure would not survive this: the C each row names hashes as recorded, the
    configuration refitted renders that very C, the measured cycles sit near the static estimate,
    and the simulator run again on the C on disk gives the same cycles and flash."""
    out, m = searched
    problem = pipeline.problem_for(out)
    rows = _verified(m)
    assert any(r["c_dir"].startswith("targets/front/") for r in rows), [r["c_dir"] for r in rows]
    for r in rows:
        assert dir_hash(out / r["c_dir"], NAME) == r["c_hash"] == r["checks"]["avr"]["c_hash"], r["c_dir"]
        for chip in CHIPS:
            ratio = r["measured"][chip]["cycles"] / r["estimate"][chip]["cycles"]
            assert 0.7 < ratio < 1.4, (r["trial"], chip, ratio)
    again = next(r for r in rows if r["c_dir"].startswith("targets/front/"))
    impl = FAMILIES[again["family"]].fit(problem, again["config"])
    assert impl.source_hash() == again["model_hash"]
    c_dir = out / again["c_dir"]
    rerun = verify_on_target(impl, "avr", c_dir, out / "rerun")
    assert dir_hash(c_dir, NAME) == again["c_hash"] == rerun["c_hash"]
    assert (rerun["cycles"], rerun["flash_bytes"]) == (again["measured"]["avr"]["cycles"],
                                                       again["measured"]["avr"]["flash_bytes"])


def _table_rows(html: str, table_id: str) -> list[str]:
    body = re.search(rf'<table id="{table_id}">(.*?)</table>', html, re.S).group(1)
    return re.findall(r"<tr>(.*?)</tr>", body.split("<tbody>", 1)[1], re.S)


def test_report_leads_with_the_front(searched):
    out, m = searched
    index = write_report(out)
    parser, html = parse(index)
    assert parser.imgs[0] == "search_front.png" and (index.parent / "search_front.png").is_file()
    md = (index.parent / "report.md").read_text()
    assert re.findall(r"!\[[^]]*\]\(([^)]+)\)", md)[0] == "search_front.png"
    assert html.index('id="search-front"') < html.index('id="implementations"')
    # under the figure: the sentence naming the pick, then the front's table, one row per point
    pick = m["selection"]["pick"]
    sentence = html.index("picks " + pick["describe"])
    assert html.index('src="search_front.png"') < sentence < html.index('id="search-front-table"')
    rows = _table_rows(html, "search-front-table")
    assert len(rows) == len(m["search"]["front"])
    for tr, r in zip(rows, m["search"]["front"]):
        assert r["describe"] in tr
        assert ("est." in tr) == (not r.get("measured")) and ("PICK" in tr) == r["picked"]
    assert check_numbers(parser, m) >= 3 * len(_verified(m))
    for i, r in enumerate(m["search"]["front"]):
        if r.get("measured"):
            (c,) = [c for c in parser.cells if c["attrs"].get("data-key") == f"search/front/{i}/measured/avr/cycles"]
            assert float(c["attrs"]["data-value"]) == r["measured"]["avr"]["cycles"]


def test_changed_c_hides_a_front_point_and_no_search_no_front(searched, tmp_path):
    src, m = searched
    out = tmp_path / "copy"
    shutil.copytree(src, out, ignore=shutil.ignore_patterns("report", "avr", "pic18", "rerun"))
    i, r = next((i, r) for i, r in enumerate(m["search"]["front"]) if (r.get("c_dir") or "").startswith("targets/"))
    c = out / r["c_dir"] / f"{NAME}.c"
    c.write_text(c.read_text() + "\n/* edited */\n")
    parser, html = parse(write_report(out))
    assert not [c for c in parser.cells if (c["attrs"].get("data-key") or "").startswith(f"search/front/{i}/measured")]
    assert f"the C in {r['c_dir']}/ changed since it was measured" in html
    assert [c for c in parser.cells if (c["attrs"].get("data-key") or "").startswith("search/front/")
            and "/measured/" in c["attrs"]["data-key"]], "the other points keep their measurements"
    assert "implementations_front.png" not in parser.imgs  # the front's figure shows the families' bests
    # without a search (or with a ladder's selection since) the report is as before: no front section, the
    # families picture first
    metrics = json.loads((out / "metrics.json").read_text())
    for variant in ("no search", "a ladder's selection since"):
        m2 = copy.deepcopy(metrics)
        if variant == "no search":
            del m2["search"]
        else:
            m2["selection"]["source"] = "ladder"
        (out / "metrics.json").write_text(json.dumps(m2))
        index = write_report(out)
        parser, html = parse(index)
        assert 'id="search-front"' not in html and not (index.parent / "search_front.png").exists()
        assert parser.imgs[0] == "implementations_front.png"


def test_run_with_search_picks_from_the_search(tmp_path, capsys):
    require_tool("simavr")
    require_tool("gpsim")
    text = (DATASETS / f"{NAME}.toml").read_text()
    text = text.replace("n_train = 1000", "n_train = 300").replace("n_test = 20000", "n_test = 2000")
    text = with_training(text, "[training]\nrestarts = 1\nadam_steps = 500\n")
    text = text.replace("max_error = 0.01", "max_error = 0.5")
    out = tmp_path / "out"
    assert main(["run", str(write_toml(tmp_path, text)), "-o", str(out), "--search", "8"]) == 0, \
        capsys.readouterr().err
    m = pipeline.load_metrics(out)
    sel, s = m["selection"], m["search"]
    assert sel["source"] == "search" and s["trials"]["complete"] + s["trials"]["pruned"] == 8
    assert _verified(m) and all(r["bit_exact"] for r in _verified(m))
    assert dir_hash(out / "c", NAME) == next(r for r in sel["implementations"] if r["picked"])["c_hash"]
    # the full run measured the float math.h IK: the front's figure draws it as the reference
    assert m["targets"]["avr"]["baselines"]["float"]["cycles"] > 0
    html = (out / "report" / "index.html").read_text()
    assert parse(out / "report" / "index.html")[0].imgs[0] == "search_front.png"
    assert "the dashed line is the float math.h IK" in html


def test_pick_sentence_gives_the_ratio_to_another_family(searched, tmp_path):
    """The sentence under the figure: the pick against the cheapest measured point of another family
    that meets the target, as a cycles ratio on the chip (here a measured lut point called poly)."""
    src, m = searched
    out = tmp_path / "copy"
    shutil.copytree(src, out, ignore=shutil.ignore_patterns("report", "avr", "pic18", "rerun"))
    metrics = copy.deepcopy(m)
    chip = metrics["selection"]["target"]["chip"]
    other = next(r for r in metrics["search"]["front"] if r.get("measured") and not r["picked"])
    other["family"] = "poly"
    pick = next(r for r in metrics["selection"]["implementations"] if r["picked"])
    (out / "metrics.json").write_text(json.dumps(metrics))
    html = write_report(out).read_text()
    ratio = other["measured"][chip]["cycles"] / pick["cycles"][chip]
    assert ratio > 1
    assert (f"The best point of another family that meets the target, {other['describe']}" in html
            and f"the pick is {ratio:.2f}x faster on {chip}" in html), ratio
    # with the other point's C changed since, it is no longer a measured point to compare with
    c = out / other["c_dir"] / f"{NAME}.c"
    c.write_text(c.read_text() + "\n/* edited */\n")
    assert f"the pick is {ratio:.2f}x faster" not in write_report(out).read_text()


def test_an_mlp_front_point_runs_on_avr_and_not_through_sdcc(galvo_run, tmp_path):
    """An MLP front point other than the MLP's best runs on the host and simavr; on pic18 it keeps
    its estimate and says why (SDCC takes minutes per MLP), and it still counts as verified."""
    require_tool("simavr")
    from nnik import selection as sel
    from nnik.search.study import _candidate
    from nnik.implementations.mlp.family import fast_problem

    out = _copy_run(galvo_run, tmp_path / "m")
    problem = fast_problem(pipeline.problem_for(out))
    cfg = {"hidden": [3], "mode": "residual", "kernel": "fast", "tanh": "default", "weight_bits": 16}
    c = _candidate(problem, "mlp", cfg)
    assert c.impl is not None, c.skipped
    row = {"trial": 7, "family": "mlp", "config": cfg, "pre_max": c.acc["pre_max"]}
    target = {"chip": "avr", "max_error": 2 * c.acc["pre_max"]}
    info = search_front.verify_front(out, [row], {search_front.config_key("mlp", cfg): c}, {}, target,
                                     out / "c" / sel.ALT_DIR)
    assert info["verified"] == info["run_here"] == 1
    assert set(row["measured"]) == {"avr"} and row["measured"]["avr"]["cycles"] > 100
    assert row["checks"]["pic18"] == {"not_run": FAMILIES["mlp"].front_not_checked_reason}
    assert row["bit_exact"] is True and row["checks"]["host"]["mismatches"] == 0
