"""Where `nnik search` keeps its study: an Optuna journal file in OUTDIR by default (no server,
safe with several local processes), or a database URL (``postgresql://...``) that workers on
several machines share. A study records the scenario's fingerprint; one made for another
scenario is refused."""

from __future__ import annotations

import time
import warnings
from pathlib import Path

from nnik.errors import NnikError

JOURNAL_FILE = "search.journal"
FINGERPRINT_ATTR = "scenario_fingerprint"
RACE_RETRIES = 3
RDB_SCHEMES = ("postgresql", "postgresql+psycopg2", "postgresql+psycopg", "sqlite")


JOURNAL_SCHEME = "journal"  # journal:///PATH: a journal file that processes in several directories share


def storage_kind(url: str | None) -> str:
    if url is None:
        return "journal"
    return url.split("://", 1)[0].split("+", 1)[0]


def is_journal(path: Path) -> bool:
    """A file an Optuna journal may append to: absent, empty, or one whose first line is a
    journal record (never a scenario, a model or any other file named by mistake)."""
    import json

    if not path.exists():
        return True
    try:
        with open(path, "rb") as f:
            first = f.readline(1 << 16)
        return first == b"" or "op_code" in json.loads(first)
    except (OSError, ValueError, TypeError):
        return False


def _journal(path: Path):
    from optuna.storages.journal import JournalFileBackend, JournalFileOpenLock, JournalStorage

    return JournalStorage(JournalFileBackend(str(path), lock_obj=JournalFileOpenLock(str(path))))


def open_storage(url: str | None, outdir: Path):
    """The Optuna storage for ``url`` (None: OUTDIR/search.journal; journal:///PATH: that file)."""
    import optuna

    if url is None:
        return _journal(outdir / JOURNAL_FILE)
    scheme = url.split("://", 1)[0] if "://" in url else None
    if scheme == JOURNAL_SCHEME:
        path = Path(url.split("://", 1)[1])
        if not path.parent.is_dir() or path.is_dir():
            raise NnikError(f"storage URL {url!r}: {path} must be a file in an existing directory", "--storage")
        if not is_journal(path):
            raise NnikError(f"storage URL {url!r}: {path} exists and is not an Optuna journal; nnik appends only to "
                            "its own journals, choose a new file", "--storage")
        return _journal(path)
    if scheme not in RDB_SCHEMES:
        raise NnikError(f"storage URL {url!r}: expected postgresql://USER@HOST:PORT/DB, sqlite:///FILE or "
                        "journal:///FILE", "--storage")
    if scheme == "postgresql":  # the driver nnik depends on (SQLAlchemy 2.1 would look for psycopg 3)
        url = "postgresql+psycopg2://" + url.split("://", 1)[1]
    for attempt in range(RACE_RETRIES + 1):
        try:
            with warnings.catch_warnings():  # the heartbeat (a dead worker's trial is failed) is "experimental"
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                return optuna.storages.RDBStorage(url, engine_kwargs=_engine_kwargs(scheme), heartbeat_interval=60,
                                                  grace_period=180)
        except Exception as exc:  # sqlalchemy's errors: bad URL, unreachable server, bad credentials
            msg = _first_line(exc)
            # workers starting together on a new database race to create its tables: the loser retries
            if attempt < RACE_RETRIES and ("duplicate key" in msg or "already exists" in msg):
                time.sleep(1.0 + attempt)
                continue
            raise NnikError(f"storage {_redact(url)}: {msg}", "--storage") from None


def _engine_kwargs(scheme: str) -> dict:
    if scheme.startswith("postgresql"):
        return {"connect_args": {"connect_timeout": 5}, "pool_pre_ping": True}
    return {}


def _redact(url: str) -> str:
    """The URL without its password."""
    head, sep, tail = url.partition("://")
    if "@" in tail:
        cred, at, rest = tail.rpartition("@")
        tail = cred.split(":", 1)[0] + ":***" * (":" in cred) + at + rest
    return head + sep + tail


def _first_line(exc: BaseException) -> str:
    text = str(getattr(exc, "orig", None) or exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]


def open_study(storage, name: str, fingerprint: str, scenario: str, directions, sampler=None, create: bool = True):
    """Create or load the study ``name``; refuse one made for another scenario (NnikError)."""
    import optuna

    try:
        if create:
            study = optuna.create_study(study_name=name, storage=storage, directions=directions, sampler=sampler,
                                        load_if_exists=True)
        else:
            study = optuna.load_study(study_name=name, storage=storage, sampler=sampler)
        attrs = study.user_attrs
    except KeyError:
        raise NnikError(f"no study {name!r} in this storage (run `nnik search` first)", "--study") from None
    except ValueError as exc:
        raise NnikError(f"study {name!r}: {_first_line(exc)}", "--study") from None
    except Exception as exc:
        if type(exc).__module__.startswith("sqlalchemy"):
            raise NnikError(f"storage: {_first_line(exc)}", "--storage") from None
        raise
    got = attrs.get(FINGERPRINT_ATTR)
    if got is None and create:
        study.set_user_attr(FINGERPRINT_ATTR, fingerprint)
        study.set_user_attr("scenario", scenario)
    elif got is not None and got != fingerprint:
        raise NnikError(f"study {name!r} was made for scenario {attrs.get('scenario', '?')!r} ({got}), not for "
                        f"{scenario!r} ({fingerprint}); use another --study or storage", "--study")
    return study
