"""Whether a calibration still describes the C the generator emits."""

from __future__ import annotations

import hashlib

from nnik.estimate.calibrations import REPO_ROOT

# Files whose content decides the generated C; their hash is recorded at calibration time and a
# mismatch marks estimates as not validated (re-run the calibration).
CODEGEN_FILES = {
    "common": ("codegen/templates/model.h.j2", "codegen/runtime/nnik_flash.h", "codegen/templates/tanh.c.j2",
               "nnik/export.py"),
    "portable": ("codegen/templates/model.c.j2",),
    "fast": ("codegen/templates/model_fast.c.j2", "codegen/runtime/nnik_kernel.h", "nnik/fastc.py",
             "nnik/fastc_avr.py", "nnik/fastc_p18.py", "nnik/kernel.py"),
}


def codegen_hash(kernel: str | None = None) -> str:
    """Hash of the files that decide the generated C of a kernel (None: the portable one)."""
    h = hashlib.sha256()
    files = CODEGEN_FILES["common"] + CODEGEN_FILES.get("fast" if kernel == "fast" else "portable", ())
    for rel in files:
        p = REPO_ROOT / rel
        h.update(rel.encode())
        h.update(p.read_bytes() if p.is_file() else b"<absent>")
    return h.hexdigest()[:16]
