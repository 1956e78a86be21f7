"""The HTML/Markdown report: every picture exists and is a PNG, every number equals metrics.json,
missing parts say "not run", the table verdict (the lut family's best against the MLP) appears when it should, and Chromium renders it."""

from __future__ import annotations

import copy
import json
import math
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest

from nnik import report
from nnik.errors import NnikError
from nnik.report import accuracy, summary_rows, tanh, targets, training, write_report

from tests.conftest import DATASETS, write_toml

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
CHROMIUM = Path("/usr/bin/chromium")


# --------------------------------------------------------------------------------------------
# helpers
# --------------------------------------------------------------------------------------------


class ReportParser(HTMLParser):
    """Collects <img src>, and every <td> with its attributes and text."""

    def __init__(self):
        super().__init__()
        self.imgs: list[str] = []
        self.cells: list[dict] = []
        self.links: list[tuple[str, str]] = []
        self.scripts = 0
        self._td: dict | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.imgs.append(a["src"])
        elif tag == "td":
            self._td = {"attrs": a, "text": ""}
        elif tag == "script":
            self.scripts += 1
        elif tag == "link":
            self.links.append((a.get("rel", ""), a.get("href", "")))

    def handle_endtag(self, tag):
        if tag == "td" and self._td is not None:
            self._td["text"] = self._td["text"].strip()
            self.cells.append(self._td)
            self._td = None

    def handle_data(self, data):
        if self._td is not None:
            self._td["text"] += data


def parse(index: Path) -> tuple[ReportParser, str]:
    text = index.read_text(encoding="utf-8")
    p = ReportParser()
    p.feed(text)
    p.close()
    return p, text


def resolve(metrics: dict, key: str):
    v = metrics
    for part in key.split("/"):
        v = v[int(part)] if isinstance(v, list) else v[part]
    return v


def check_pngs(index: Path, parser: ReportParser) -> None:
    assert parser.imgs, "the report shows no pictures"
    for src in parser.imgs:
        assert "://" not in src and not src.startswith("data:") and not src.startswith("/"), src
        f = index.parent / src
        assert f.is_file(), f"missing picture {src}"
        assert f.read_bytes()[:8] == PNG_SIGNATURE, f"{src} is not a PNG"
        img = mpimg.imread(f)
        assert img.ndim == 3 and img.shape[0] > 100 and img.shape[1] > 100, (src, img.shape)
        assert float(img[..., :3].std()) > 0.01, f"{src} is blank"


def check_numbers(parser: ReportParser, metrics: dict) -> int:
    """Every <td data-key> equals metrics.json, and its text is that value rounded as shown."""
    n = 0
    for c in parser.cells:
        key = c["attrs"].get("data-key")
        if key is None:
            continue
        want = resolve(metrics, key)
        raw = c["attrs"]["data-value"]
        if isinstance(want, bool):
            assert raw == str(want).lower(), key
            continue
        assert float(raw) == float(want), (key, raw, want)
        text = c["text"]
        if "e" in text.lower():  # scientific: 3 significant digits
            assert math.isclose(float(text), want, rel_tol=6e-3), (key, text, want)
        else:
            decimals = len(text.split(".")[1]) if "." in text else 0
            assert abs(float(text) - want) <= 0.5 * 10**-decimals * (1 + 1e-9) + 1e-12, (key, text, want)
        n += 1
    return n


def by_key(parser: ReportParser, key: str) -> list[dict]:
    return [c for c in parser.cells if c["attrs"].get("data-key") == key]


def copy_run(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("report"))
    return dst


def add_synthetic_fixed(run: Path, lut_wins: bool = True, pic18: dict | None = None) -> dict:
    """Give a real run the sections other pipeline steps will write: fixed, host, tanh, targets,
    plus fixed_eval.npz made from the real model (its float predictions plus a small 'quantisation'
    error)."""
    from nnik.machine.data import Dataset
    from nnik.implementations.mlp.train import TrainedModel

    model = TrainedModel.load(run / "model.pt")
    ds = Dataset.load(run / "data.npz")
    p, q = ds.p["test"], ds.q["test"]
    q_float = model.predict(p)
    rng = np.random.default_rng(0)
    q_fixed = q_float + rng.normal(0.0, 0.01, q_float.shape)
    q_delivered = np.round(q_fixed).astype(np.int64)
    np.savez(run / "fixed_eval.npz", p_test=p, q_true=q, q_float=q_float, q_fixed=q_fixed, q_delivered=q_delivered)
    e_fix = np.abs(q_fixed - q)
    e_del = np.abs(q_delivered - q)
    mlp_err = e_del.max(0)
    m = json.loads((run / "metrics.json").read_text())
    m["fixed"] = {
        "max_abs": e_fix.max(0).tolist(),
        "rms": np.sqrt((e_fix**2).mean(0)).tolist(),
        "p99": np.percentile(e_fix, 99, axis=0).tolist(),
        "delivered_max_abs": mlp_err.tolist(),
        "tanh_variant": "lerp_mr4",
        "weights_bytes": 64,
        "q_formats": {"input": "Q3.12", "layer0": {"w": "Q2.13", "b": "Q3.12"}, "output": "Q15"},
    }
    m["host"] = {"bit_exact": True, "mismatches": 0, "points": int(len(p))}
    m["tanh"] = {"variant": "lerp_mr4", "max_lsb": 1.835022398208821, "rms_lsb": 0.623383778165939}
    lut_err = (mlp_err / 4).tolist() if lut_wins else (mlp_err * 3).tolist()
    m["targets"] = {
        "avr": {
            "bit_exact": True, "mismatches": 0, "points": 4096, "cycles": 1523.25, "cycles_max": 1602,
            "flash_bytes": 1410, "ram_bytes": 52, "clock_hz": 16000000, "compiler": "avr-gcc 5.4.0",
            "flags": "-Os -mmcu=atmega328p",
            "estimate": {"cycles": 1490, "flash_bytes": 1380, "ram_bytes": 50},
            "baselines": {
                "float": {"cycles": 7623, "flash_bytes": 3300, "ram_bytes": 24, "max_abs": [0.5, 0.5]},
            },
            "kernels": {"naive_c": {"cycles": 4166, "flash_bytes": 1900, "max_abs": mlp_err.tolist()}},
        },
        "pic18": pic18 if pic18 is not None else {"not_run": "toolchain missing"},
    }
    # the lut family's best as the selection verified it (what a firmware engineer would write)
    m["implementations"] = [{"family": "lut", "describe": "lut 40x40, int16", "delivered_max_abs": lut_err,
                             "targets": {"avr": {"cycles": 900 if lut_wins else 2100, "flash_bytes": 8200,
                                                 "ram_bytes": 12, "bit_exact": True}}}]
    (run / "metrics.json").write_text(json.dumps(m, indent=2))
    return m


PIC18_RAN = {
    "bit_exact": True, "mismatches": 0, "points": 512, "cycles": 9876.5, "cycles_max": 10500,
    "flash_bytes": 2950, "ram_bytes": 90, "clock_hz": 16000000, "compiler": "sdcc 4.2.0",
    "flags": "-mpic16 -p18f452",
    "baselines": {"float": {"cycles": 47389, "flash_bytes": 6000, "ram_bytes": 40, "max_abs": [0.5, 0.5]}},
}


LATER_STAGES = ("fixed", "host", "tanh", "baselines", "targets", "selection", "implementations")


@pytest.fixture
def galvo_copy(galvo_run, tmp_path) -> Path:
    """The galvo run as generate/train/evaluate leave it: later stages' sections and files removed
    (other tests may have exported and verified the shared run already)."""
    run = copy_run(galvo_run, tmp_path / "galvo")
    m = json.loads((run / "metrics.json").read_text())
    (run / "metrics.json").write_text(json.dumps({k: v for k, v in m.items() if k not in LATER_STAGES}))
    for f in ("fixed_eval.npz",):
        (run / f).unlink(missing_ok=True)
    shutil.rmtree(run / "c", ignore_errors=True)
    shutil.rmtree(run / "targets", ignore_errors=True)
    return run


def test_report_of_full_real_run(galvo_fixed, galvo_run, tmp_path):
    """After export, host verification and the targets: every number shown equals metrics.json."""
    from nnik import pipeline

    for t in ("avr", "pic18"):
        pipeline.verify(galvo_run, t)
    run = copy_run(galvo_run, tmp_path / "full")
    index = write_report(run)
    parser, text = parse(index)
    m = json.loads((run / "metrics.json").read_text())
    check_pngs(index, parser)
    assert check_numbers(parser, m) >= 40
    for key in ("fixed/max_abs/0", "fixed/delivered_max_abs/1", "host/points"):
        assert by_key(parser, key), f"{key} not shown"
    for t in ("avr", "pic18"):
        if "not_run" in m["targets"][t]:
            assert "not run" in text
        else:
            assert by_key(parser, f"targets/{t}/cycles"), t
    assert "fixed-point export not run" not in text


# --------------------------------------------------------------------------------------------
# a real run, as `nnik run` leaves it today (no fixed point, no targets)
# --------------------------------------------------------------------------------------------


def test_report_of_real_run(galvo_copy):
    index = write_report(galvo_copy)
    assert index == galvo_copy / "report" / "index.html"
    assert (galvo_copy / "report" / "report.md").is_file()
    parser, text = parse(index)
    m = json.loads((galvo_copy / "metrics.json").read_text())

    check_pngs(index, parser)
    assert {"error_map.png", "error_hist.png", "training_curve.png"} <= set(parser.imgs)
    assert check_numbers(parser, m) >= 20
    for key in ("float/max_abs/0", "float/max_abs/1", "float/rms/0", "float/p99/1", "affine_only/max_abs/1",
                "float/position_um/max", "network/parameters", "train_seconds", "onnx/max_abs_diff", "float/rel_pct/0"):
        assert by_key(parser, key), f"{key} not shown"

    # physical units: a galvo's mechanical degrees, 360 / 3200 per microstep
    deg = 360.0 / 3200
    assert "0.1125 mechanical deg per microstep" in text
    phys = [c for c in parser.cells if "derived" in c["attrs"].get("class", "") and c["attrs"].get("data-value")]
    assert any(math.isclose(float(c["attrs"]["data-value"]), m["float"]["max_abs"][0] * deg, rel_tol=1e-12)
               for c in phys)

    # what has not run is said, with the reason
    assert "fixed-point export not run: no <code>fixed</code> section in metrics.json" in text
    assert "not run — no <code>host</code> section in metrics.json" in text
    assert "targets not run: no <code>targets</code> section in metrics.json" in text
    assert "Float64 MLP error on a regular 161×161 grid" in text
    for t in ("avr", "pic18"):
        assert f"C on {t}" in text
    # published references, labelled as such, beside this run
    assert text.count("published (seed 000)") == 3 and text.count("published (seed 004)") == 2
    for v in ("1977", "258.6", "2696", "38.0", "3590", "7.2", "5.1851", "13.6855", "0.0508", "0.2008"):
        assert f">{v}<" in text, v
    # self-contained
    assert parser.scripts == 0 and not parser.links
    assert "http://" not in text and "https://" not in text and "@import" not in text


def test_markdown_tables_are_rectangular(galvo_copy):
    add_synthetic_fixed(galvo_copy)
    write_report(galvo_copy)
    md = (galvo_copy / "report" / "report.md").read_text()
    lines = md.splitlines()
    i = 0
    n_tables = 0
    while i < len(lines):
        if lines[i].startswith("| ") and i + 1 < len(lines) and lines[i + 1].startswith("|---"):
            width = len(re.split(r"(?<!\\)\|", lines[i]))
            j = i + 2
            while j < len(lines) and lines[j].startswith("| "):
                assert len(re.split(r"(?<!\\)\|", lines[j])) == width, (lines[i], lines[j])
                j += 1
            n_tables += 1
            i = j
        else:
            i += 1
    assert n_tables >= 8
    assert "![error heatmap over the workspace](error_map.png)" in md
    assert "toolchain missing" in md


# --------------------------------------------------------------------------------------------
# everything present (synthetic sections other issues will write)
# --------------------------------------------------------------------------------------------


def test_full_report_with_lut_winning(galvo_copy, tmp_path):
    m = add_synthetic_fixed(galvo_copy, lut_wins=True)
    out = tmp_path / "elsewhere"
    index = write_report(galvo_copy, out)
    assert index == out / "index.html"
    parser, text = parse(index)
    check_pngs(index, parser)
    # every picture of the MLP's sections is there; sections without data here (families, jobs) show none
    mlp_pngs = {png for sec in (accuracy, tanh, targets, training) for png in sec.PNGS}
    from nnik.report import jobs

    fixed_names = {png for png in parser.imgs if not png.startswith(jobs.PNG_PREFIX)}  # job_<job>.png vary
    assert mlp_pngs <= fixed_names <= set(report.ALL_PNGS)
    assert check_numbers(parser, m) >= 60
    for key in ("fixed/max_abs/0", "fixed/rms/1", "fixed/p99/0", "fixed/delivered_max_abs/1", "fixed/weights_bytes",
                "host/mismatches", "host/points", "tanh/max_lsb", "tanh/rms_lsb",
                "targets/avr/cycles", "targets/avr/cycles_max", "targets/avr/flash_bytes", "targets/avr/ram_bytes",
                "targets/avr/estimate/cycles", "implementations/0/targets/avr/cycles", "targets/avr/baselines/float/cycles",
                "implementations/0/delivered_max_abs/0", "targets/avr/kernels/naive_c/cycles"):
        assert by_key(parser, key), f"{key} not shown"
    # µs at the stated clock, and the estimator's difference
    assert any(c["text"] == "95.2" for c in parser.cells)  # 1523.25 cycles / 16 MHz
    assert any(c["text"] == "-2.2" for c in parser.cells)  # (1490 - 1523.25) / 1523.25
    assert "On avr the lut family's best wins over the nnik MLP" in text
    assert "pic18" in text and "not run — toolchain missing" in text
    assert "fixed-point export not run" not in text
    assert "Fixed-point error over the workspace" in text
    assert "Q format: layer0.w" in text
    md = (out / "report.md").read_text()
    assert "lut family's best wins" in md

    rows = summary_rows(m)
    assert all(len(r) == len(report.SUMMARY_HEADER) for r in rows)
    d = {r[0]: r for r in rows}
    assert d["mlp on avr"][1].startswith("1523 cycles = 95.2 µs @ 16 MHz")
    assert d["mlp on pic18"][1:] == ("not run", "toolchain missing")
    assert d["lut family best"][1] == "wins"


def test_lut_not_winning_and_pic18_timing(galvo_copy):
    m = add_synthetic_fixed(galvo_copy, lut_wins=False, pic18=copy.deepcopy(PIC18_RAN))
    index = write_report(galvo_copy)
    parser, text = parse(index)
    check_numbers(parser, m)
    assert "lut family's best wins" not in text
    assert "is not both faster and more accurate" in text
    assert "not run" not in text.split('id="targets"')[1].split("</section>")[0].replace("table comparison not run", "")
    # PIC18: 4 clocks per instruction cycle; 9876.5 cycles at 16 MHz = 2469.1 µs
    assert any(c["text"] == "2469.1" for c in parser.cells)
    assert by_key(parser, "targets/pic18/baselines/float/cycles")
    assert "this run, pic18 @ 16 MHz, sdcc 4.2.0" in text


def test_target_not_bit_exact_is_flagged(galvo_copy):
    m = add_synthetic_fixed(galvo_copy)
    m["targets"]["avr"]["bit_exact"] = False
    m["targets"]["avr"]["mismatches"] = 3
    m["host"] = {"bit_exact": True, "mismatches": 0, "points": 10}
    (galvo_copy / "metrics.json").write_text(json.dumps(m))
    index = write_report(galvo_copy)
    _, text = parse(index)
    assert "NOT bit-exact with the integer model: 3 mismatches" in text
    assert dict((r[0], r) for r in summary_rows(m))["mlp on avr"][2].endswith("NOT bit-exact (3 mismatches)")


# --------------------------------------------------------------------------------------------
# whatever is missing
# --------------------------------------------------------------------------------------------


def test_only_metrics_json(galvo_copy):
    for f in ("model.pt", "data.npz", "model.onnx"):
        (galvo_copy / f).unlink()
    index = write_report(galvo_copy)
    parser, text = parse(index)
    m = json.loads((galvo_copy / "metrics.json").read_text())
    check_numbers(parser, m)
    assert "training curve not run: model.pt not found" in text
    assert "error map not run" in text
    assert "error histogram not run" in text
    # the scenario is found again from the path in metrics.json, if it exists from here
    for src in parser.imgs:
        assert (index.parent / src).is_file()


def test_stale_pictures_are_removed(galvo_copy):
    write_report(galvo_copy)
    assert (galvo_copy / "report" / "training_curve.png").is_file()
    (galvo_copy / "model.pt").unlink()
    write_report(galvo_copy)
    assert not (galvo_copy / "report" / "training_curve.png").exists()


def test_activations_missing(galvo_copy, monkeypatch):
    monkeypatch.setitem(sys.modules, "nnik.implementations.mlp.tanh", None)  # import now raises ImportError
    index = write_report(galvo_copy)
    parser, text = parse(index)
    assert "tanh error plot not available: nnik.implementations.mlp.tanh could not be imported" in text
    assert "tanh_error.png" not in parser.imgs
    check_pngs(index, parser)


def test_no_metrics_is_one_clear_error(tmp_path):
    with pytest.raises(NnikError, match="metrics.json not found"):
        write_report(tmp_path)
    (tmp_path / "metrics.json").write_text("{not json")
    with pytest.raises(NnikError, match="corrupt metrics file"):
        write_report(tmp_path)


def test_sibling_no_normalize_run_is_shown(galvo_copy, tmp_path):
    sib = tmp_path / "galvo-no-normalize"
    sib.mkdir()
    m = json.loads((galvo_copy / "metrics.json").read_text())
    m["network"]["normalize"] = False
    m["float"]["rel_pct"] = [0.5505, 0.3097]
    (sib / "metrics.json").write_text(json.dumps(m))
    _, text = parse(write_report(galvo_copy))
    assert "sibling galvo-no-normalize" in text and 'data-value="0.5505"' in text


# --------------------------------------------------------------------------------------------
# a measured machine: no analytic model, held-out rows, belt micrometres
# --------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def measured_run(tmp_path_factory) -> Path:
    from nnik import pipeline
    from nnik.machine.scenario import load_scenario

    d = tmp_path_factory.mktemp("measured")
    csv = (DATASETS / "corexy_measured.csv").resolve()
    toml = write_toml(d, f"""
name = "corexy_measured_small"
[mechanism]
kind = "measured"
csv = "{csv}"
[actuator]
kind = "stepper"
mm_per_rev = 40.0
[workspace]
x_mm = [0.0, 200.0]
y_mm = [0.0, 200.0]
[network]
hidden = [4]
mode = "residual"
[training]
restarts = 1
adam_steps = 200
lbfgs_rounds = 20
""")
    scn = load_scenario(toml)
    out = d / "run"
    pipeline.generate(scn, out)
    pipeline.train(scn, out, progress=False)
    pipeline.evaluate(out)
    return out


def test_measured_report(measured_run, tmp_path):
    index = write_report(measured_run, tmp_path / "r")
    parser, text = parse(index)
    m = json.loads((measured_run / "metrics.json").read_text())
    assert "position_um" not in m["float"]
    check_pngs(index, parser)
    check_numbers(parser, m)
    assert "12.5 µm of belt per microstep" in text
    assert "held-out measured points" in text
    assert not [c for c in parser.cells if c["text"] == "head position"]  # no forward model, no position error


# --------------------------------------------------------------------------------------------
# rendered by a real browser
# --------------------------------------------------------------------------------------------


def test_chromium_renders_non_blank(galvo_copy, tmp_path):
    if not CHROMIUM.exists():
        if os.environ.get("NNIK_REQUIRE_TOOLCHAINS") == "1":
            pytest.fail(f"{CHROMIUM} not found and NNIK_REQUIRE_TOOLCHAINS=1 (run scripts/install_chromium.sh)")
        pytest.skip(f"{CHROMIUM} not found (run scripts/install_chromium.sh to enable this test)")
    add_synthetic_fixed(galvo_copy)
    index = write_report(galvo_copy)
    shot = tmp_path / "shot.png"
    cmd = [str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
           "--disable-background-networking", "--disable-component-update", "--disable-sync",
           f"--user-data-dir={tmp_path / 'profile'}", f"--screenshot={shot}", "--window-size=1200,2000",
           index.resolve().as_uri()]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert shot.is_file(), f"chromium wrote no screenshot (rc {r.returncode}): {r.stderr[-2000:]}"
    assert shot.read_bytes()[:8] == PNG_SIGNATURE
    img = mpimg.imread(shot)[..., :3]
    assert img.shape[:2] == (2000, 1200)
    bg = img[-1, -1]  # the page's background colour
    differs = np.abs(img - bg).max(axis=2) > 0.05
    assert differs.mean() > 0.01, f"screenshot is blank ({differs.mean():.4%} of pixels differ)"
    # the blue header band is drawn at the top
    top = img[5:40, 5:200].reshape(-1, 3).mean(0)
    assert top[2] > top[0] + 0.2, top
