"""Is there a finished pick in OUTDIR, and are c/NAME.{c,h} on disk the bytes that were verified?

The one place every command asks: `nnik report` marks the pick with the answer, `nnik job` and
`nnik export --arduino` deliver only a pick whose answer is yes (else one line, exit 2), and
`nnik verify` re-verifies the bytes on disk and records the result here.

``OUTDIR/pick.json`` is the completion marker of `nnik run`, `nnik select` and `nnik search`. It
is written atomically and LAST, after c/NAME.{c,h}, c/alt/ and metrics.json's selection, and it
is removed FIRST by every step that changes what a pick depends on (generate, train, evaluate,
select, the search's verification). It holds the pick's identity (family, configuration, model
hash), the hash of the C that was verified, every verification result (each carrying the hash
of the C it ran), the target the pick was made for and the hashes of the model.pt and data.npz it
was made from. A kill at any moment therefore leaves either no marker (nothing is delivered) or a
marker whose hashes say whether the files on disk are still the ones it describes.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from nnik.files.c_hash import dir_hash
from nnik.errors import NnikError

PICK_FILE = "pick.json"
VERSION = 1
INPUT_FILES = ("model.pt", "data.npz")  # what every family's fit depends on (the MLP's on both)
CHECKS = ("host", "avr", "avr_portable", "pic18", "pic18_portable")


@dataclass
class PickStatus:
    ok: bool  # a finished pick whose C on disk is the C that was verified, meeting its target
    state: str  # verified | none | corrupt | other_model | missing | changed | unverified | misses_target
    message: str  # one line, naming the command that mends it
    name: str = ""
    disk_hash: str | None = None
    verified_hash: str | None = None
    marker: dict | None = None

    @property
    def file(self) -> str:
        return f"c/{self.name}.c"

    def check(self, key: str) -> dict | None:
        """A verification result of the C on disk (None if there is none for these bytes)."""
        r = ((self.marker or {}).get("checks") or {}).get(key)
        if isinstance(r, dict) and self.disk_hash and r.get("c_hash") == self.disk_hash:
            return r
        return None


def marker_path(outdir: Path) -> Path:
    return Path(outdir) / PICK_FILE


def invalidate(outdir: Path) -> None:
    """Remove the completion marker (first thing a step that rewrites the pick's inputs does)."""
    from nnik.files.atomic_write import fsync_dir

    p = marker_path(outdir)
    if p.exists():
        p.unlink()
        fsync_dir(p.parent)


def _file_hash(p: Path) -> str | None:
    return hashlib.sha256(p.read_bytes()).hexdigest()[:16] if p.is_file() else None


def inputs_hash(outdir: Path) -> dict:
    return {f: _file_hash(Path(outdir) / f) for f in INPUT_FILES}


def selection_digest(section: dict) -> str:
    """Identity of metrics.json's selection as far as the pick goes (its pick and its target)."""
    key = {"pick": section.get("pick"), "target": section.get("target")}
    return hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()[:16]


def seal(outdir: Path, section: dict) -> dict:
    """Write the marker for the pick of ``section`` (metrics.json's selection, already written, and
    c/NAME.{c,h}, already in place): the last step of run, select and search."""
    from nnik.files.atomic_write import write_file_atomic

    outdir = Path(outdir)
    row = next(r for r in section["implementations"] if r.get("picked"))
    name = section["pick"]["file"].removesuffix(".c")
    on_disk = dir_hash(outdir / "c", name)
    if on_disk != row.get("c_hash"):
        raise NnikError(f"c/{name}.c ({on_disk}) is not the C that was verified ({row.get('c_hash')}); "
                        f"run `nnik select {outdir}` again", str(outdir))
    checks = {"host": row.get("host"), **(row.get("targets") or {})}
    marker = {
        "version": VERSION, "name": name, "file": f"c/{name}.c", "c_hash": on_disk,
        "family": row["family"], "config": row["config"], "describe": row.get("describe"),
        "model_hash": row.get("model_hash"), "pre_max": row["pre_max"], "target": section["target"],
        "input_unit_um": section.get("input_unit_um", 1.0), "source": section.get("source", "ladder"),
        "checks": {k: v for k, v in checks.items() if isinstance(v, dict)},
        "inputs": inputs_hash(outdir), "selection": selection_digest(section),
    }
    write_file_atomic(marker_path(outdir), json.dumps(marker, indent=2) + "\n")
    return marker


def _read_marker(outdir: Path) -> dict | None | str:
    """The marker, None without one, or what is wrong with it (one phrase naming the key)."""
    from nnik.files import json_shape

    p = marker_path(outdir)
    if not p.is_file():
        return None
    try:
        m = json.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return "is unreadable (an interrupted write?)"
    problem = json_shape.problem(m, json_shape.PICK)
    if problem:
        return f"is not one nnik wrote: {problem}"
    if m["version"] != VERSION:
        return f"is of another version ({m['version']}, this nnik writes {VERSION})"
    return m


def _metrics_selection(outdir: Path) -> dict | None:
    try:
        sel = json.loads((Path(outdir) / "metrics.json").read_text(encoding="utf-8")).get("selection")
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, AttributeError):
        return None
    return sel if isinstance(sel, dict) else None


def status(outdir: Path, name: str | None = None) -> PickStatus:
    """The pick's state; ``name`` (the scenario's) only matters when there is no marker."""
    outdir = Path(outdir)
    select = f"run `nnik select {outdir}`"
    m = _read_marker(outdir)
    if m is None:
        sel = _metrics_selection(outdir)
        nm = name or ((sel or {}).get("pick") or {}).get("file", "NAME.c").removesuffix(".c")
        if sel is not None and sel.get("pick") is None and "implementations" in sel:
            why = "the last selection found no implementation that meets [target]"
        else:
            why = "the last `nnik run`, `nnik select` or `nnik search` did not finish"
        there = f"; c/{nm}.c is not a finished pick" if (outdir / "c" / f"{nm}.c").is_file() else ""
        return PickStatus(False, "none", f"no finished pick here ({why}{there}); {select}", nm)
    if isinstance(m, str):
        return PickStatus(False, "corrupt", f"{PICK_FILE} {m}; {select}", name or "")
    st = PickStatus(False, "", "", m["name"], dir_hash(outdir / "c", m["name"]), m["c_hash"], m)
    if m["inputs"] != inputs_hash(outdir):
        changed = [f for f in INPUT_FILES if m["inputs"].get(f) != inputs_hash(outdir)[f]]
        st.state, st.message = "other_model", (f"the pick in {st.file} was made from another {' and '.join(changed)} "
                                               f"than this directory holds now; {select}")
        return st
    sel = _metrics_selection(outdir)
    if sel is None or selection_digest(sel) != m.get("selection"):
        st.state, st.message = "other_model", f"metrics.json's selection is not the one that made {st.file}; {select}"
        return st
    if st.disk_hash is None:
        st.state, st.message = "missing", f"{st.file} or its header is missing; {select}"
        return st
    chip = m["target"]["chip"]
    verify = f"`nnik verify {outdir} --target {chip}`"
    if st.disk_hash != m["c_hash"]:
        st.state = "changed"
        st.message = (f"{st.file} is NOT the C that was verified (on disk {st.disk_hash}, verified {m['c_hash']}); "
                      f"run {verify} to verify these bytes, or `nnik select {outdir}` to write the verified pick again")
        return st
    bad = [k for k in CHECKS if st.check(k) and "not_run" not in st.check(k) and not st.check(k).get("bit_exact")]
    if bad:
        st.state = "unverified"
        st.message = (f"{st.file} ({st.disk_hash}) is NOT bit-exact with the pick's integer model on "
                      f"{', '.join(bad)}; `nnik select {outdir}` writes the verified pick again")
        return st
    missing = [k for k in ("host", chip) if not (st.check(k) or {}).get("bit_exact")]
    if missing:
        st.state = "unverified"
        st.message = (f"{st.file} ({st.disk_hash}) has not been verified on {' and '.join(missing)}; run {verify}")
        return st
    tg, res = m["target"], st.check(chip)
    why = []
    if not m["pre_max"] <= tg["max_error"]:
        why.append(f"max error {m['pre_max']:.4g} > max_error {tg['max_error']:g}")
    if tg.get("max_cycles") and not res.get("cycles", float("inf")) <= tg["max_cycles"]:
        why.append(f"{res.get('cycles', float('nan')):.0f} cycles > max_cycles {tg['max_cycles']:g}")
    if tg.get("max_flash_bytes") and not res.get("flash_bytes", float("inf")) <= tg["max_flash_bytes"]:
        why.append(f"{res.get('flash_bytes')} B > max_flash_bytes {tg['max_flash_bytes']}")
    if why:
        st.state, st.message = "misses_target", f"{st.file} misses its [target]: {'; '.join(why)}; {select}"
        return st
    st.ok, st.state = True, "verified"
    st.message = (f"{st.file} is the verified pick ({m['family']}, C hash {st.disk_hash}): bit-exact on host and "
                  f"{chip}, {res['cycles']:.0f} cycles and {res['flash_bytes']} B on {chip}")
    return st


def require_deliverable(outdir: Path, what: str) -> PickStatus:
    """The pick, ready to become firmware (``what``: the command, for the message); else NnikError.
    The G-code firmware passes whole micrometres, so a pick in other input units is refused too."""
    st = status(outdir)
    if not st.ok:
        raise NnikError(f"{what}: {st.message}", str(outdir))
    unit = st.marker.get("input_unit_um", 1.0)
    if unit != 1.0:
        raise NnikError(f"{what}: the pick in {st.file} takes inputs in units of {unit:g} um, but the G-code firmware "
                        "passes whole micrometres ([export] input_unit_um = 1 is needed)", str(outdir))
    return st


def record(outdir: Path, marker: dict, results: dict) -> bool:
    """Record verification results of c/NAME.c as it is on disk (``nnik verify``): only when every
    run was bit-exact on the same bytes; the marker then describes these bytes (results of other
    bytes stay in it, but no longer count). Returns whether anything was recorded."""
    from nnik.files.atomic_write import write_file_atomic

    ran = {k: r for k, r in results.items() if isinstance(r, dict) and "not_run" not in r}
    hashes = {r.get("c_hash") for r in ran.values()}
    if not ran or not all(r.get("bit_exact") for r in ran.values()) or len(hashes) != 1 or None in hashes:
        return False
    m = {**marker, "c_hash": hashes.pop(), "checks": {**marker["checks"], **ran}}
    write_file_atomic(marker_path(outdir), json.dumps(m, indent=2) + "\n")
    return True
