#!/usr/bin/env bash
# Install what leap needs to build and run on Debian or Ubuntu, if missing:
# Simbody 3.7 (libsimbody-dev), pkg-config and a C++ compiler. Needs root or sudo
# only when something is missing. The Rust toolchain itself comes from rustup.
set -euo pipefail

missing=()
pkg-config --exists simbody 2>/dev/null || missing+=(libsimbody-dev)
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
command -v g++ >/dev/null 2>&1 || missing+=(g++)

if ((${#missing[@]})); then
    echo "installing: ${missing[*]}" >&2
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
            echo "error: need root (or sudo) to install ${missing[*]}" >&2; exit 1
        fi
    fi
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y "${missing[@]}"
fi

if ! command -v cargo >/dev/null 2>&1; then
    echo "error: cargo not found: install the Rust toolchain (1.89 or newer) with rustup, then rerun" >&2
    exit 1
fi
