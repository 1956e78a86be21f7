"""Two processes sharing one study: each says how many trials it ran itself and how many the
study holds, and the two counts add up to the study's (a journal file both directories name with
--storage journal:///FILE, and a PostgreSQL server where the search tests start one)."""

from __future__ import annotations

import re

import pytest

from tests.bad_input import tiny_run  # noqa: F401 (fixture)
from tests.search.test_search import FINISHED, _cli, _copy_run, _study, postgres  # noqa: F401 (fixture)

LINE = re.compile(r"search: (\d+) trials run by this command \(1 local job\) in .*; the study holds (\d+) finished "
                  r"trials \(asked for (\d+)(?:; (\d+) run meanwhile by other workers)?\)")


def two_workers(run, tmp_path, url: str, n: int = 10) -> tuple[list[tuple[int, ...]], list]:
    a, b = _copy_run(run, tmp_path / "a"), _copy_run(run, tmp_path / "b")  # two machines
    procs = [_cli(d, "--trials", n, "--worker", "--families", "lut", "--storage", url) for d in (a, b)]
    counts = []
    for p in procs:
        out, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
        m = LINE.search(" ".join(out.split()))
        assert m, out
        counts.append(tuple(int(g or 0) for g in m.groups()))
    trials = [t for t in _study(a, url).get_trials() if t.state in FINISHED]
    return counts, trials


def check(counts, trials, n: int = 10) -> None:
    (ran_a, held_a, asked_a, others_a), (ran_b, held_b, asked_b, others_b) = counts
    assert asked_a == asked_b == n
    assert ran_a + ran_b == len(trials)  # together they ran what the study holds (n, or n + 1)
    assert n <= len(trials) <= n + 1 and max(held_a, held_b) == len(trials)
    assert ran_a + others_a == held_a and ran_b + others_b == held_b  # a new study: all added meanwhile
    per_worker = {}
    for t in trials:
        per_worker[t.user_attrs["worker"]] = per_worker.get(t.user_attrs["worker"], 0) + 1
    assert sorted(per_worker.values()) == sorted([ran_a, ran_b])
    assert ran_a < held_a or ran_b < held_b


def test_two_workers_count_their_own_trials_on_a_journal_file(tiny_run, tmp_path):
    url = f"journal://{tmp_path / 'shared.journal'}"
    check(*two_workers(tiny_run, tmp_path, url))


def test_two_workers_count_their_own_trials_on_postgres(tiny_run, tmp_path, postgres):
    check(*two_workers(tiny_run, tmp_path, postgres))


def test_journal_storage_in_a_missing_directory_is_one_line(tiny_run, tmp_path, capsys):
    from nnik.cli import main

    rc = main(["search", str(tiny_run), "--trials", "1", "--worker", "--storage", f"journal://{tmp_path}/no/such.journal"])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and "must be a file in an existing directory" in err[0], err
