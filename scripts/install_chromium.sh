#!/usr/bin/env bash
# Install a headless-capable Chromium (Debian package `chromium`), used by tests/report/test_report.py
# to render the HTML report and check that the page is not blank.
#
# Idempotent: does nothing when /usr/bin/chromium is already there. Needs root (or sudo).
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive

log() { printf '[install_chromium] %s\n' "$*" >&2; }

if [ -x /usr/bin/chromium ]; then
    log "chromium already installed: $(/usr/bin/chromium --version 2>/dev/null || echo '?')"
    exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null 2>&1; then
        SUDO="sudo"
    else
        log "ERROR: must run as root (or have sudo) to install chromium"
        exit 1
    fi
fi

# The package lists may be missing on a fresh machine; refresh them only if the install fails.
if ! $SUDO apt-get install -y --no-install-recommends chromium; then
    log "apt-get install failed; refreshing package lists and retrying"
    $SUDO apt-get update
    $SUDO apt-get install -y --no-install-recommends chromium
fi
log "installed: $(/usr/bin/chromium --version 2>/dev/null || echo '?')"
