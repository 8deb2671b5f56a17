#!/usr/bin/env bash
# scripts/test.sh: THE test command of mvgrasp. Runs every check and every test:
#   cargo fmt --check; cargo clippy -D warnings; cargo test (the Rust workspace without the
#   pyo3 crate, so this part needs no Python; in the `dist` profile, the wheel's, so that the
#   optimised dependencies are built once for both); clippy on the pyo3 crate; the wheel built by
#   maturin and tested with pytest (py/tests); the training package tested with pytest
#   (training/tests).
#
# It installs nothing from the network and assumes the tools are there (.ci/run installs them
# on a fresh Debian machine):
#   - cargo with the rustfmt and clippy components;
#   - a Python >= 3.10 environment holding maturin>=1.16,<2, pytest, numpy, setuptools>=77,
#     ray>=2.9, safetensors, matplotlib and torch>=2 (the training tests run, never skip, here).
#
# Python environment: the active virtualenv ($VIRTUAL_ENV) when there is one, else ./.venv at
# the repository root (make it with .ci/run, or by hand:
#   python3 -m venv .venv && .venv/bin/pip install 'maturin>=1.16,<2' pytest numpy 'setuptools>=77' 'ray>=2.9' \
#       safetensors matplotlib torch).
# The wheel is built into target/wheels/mvgrasp/ (emptied first; outside any venv) and installed
# into that environment with --force-reinstall --no-deps; training/ is installed editable.
#
# Usage: scripts/test.sh   (from any folder; it works in the repository root)
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT=$PWD
WHEEL_DIR=$ROOT/target/wheels/mvgrasp

SCRIPT_START=$(date +%s)
SECTION=""
SECTION_START=$SCRIPT_START

section() {
    end_section
    SECTION=$1
    SECTION_START=$(date +%s)
    printf '\n=== %s\n' "$SECTION"
}

end_section() {
    if [[ -n $SECTION ]]; then
        printf -- '--- %s: %ds\n' "$SECTION" "$(($(date +%s) - SECTION_START))"
        SECTION=""
    fi
}

on_exit() {
    local status=$?
    if [[ $status -ne 0 && -n $SECTION ]]; then
        printf '\nFAILED in "%s" after %ds (exit %d)\n' "$SECTION" \
            "$(($(date +%s) - SECTION_START))" "$status" >&2
    fi
}
trap on_exit EXIT

die() {
    printf 'scripts/test.sh: %s\n' "$*" >&2
    exit 1
}

# --- Python environment, checked before the long Rust build so a missing tool fails fast.
if [[ -n ${VIRTUAL_ENV:-} ]]; then
    VENV=$VIRTUAL_ENV
elif [[ -x $ROOT/.venv/bin/python ]]; then
    VENV=$ROOT/.venv
else
    die "no Python environment: activate a virtualenv or create .venv (run .ci/run, or see the top of this script)"
fi
PY=$VENV/bin/python
[[ -x $PY ]] || die "$PY not found (VIRTUAL_ENV=$VENV)"
export PATH="$VENV/bin:$PATH"
"$PY" - <<'PYCHECK' || die "the Python environment $VENV lacks tools (see the top of this script)"
import importlib.metadata as md
import sys

def version(name):
    try:
        return tuple(int(part) for part in md.version(name).split(".")[:2])
    except (md.PackageNotFoundError, ValueError):
        return None

wants = {
    "maturin": lambda v: (1, 16) <= v < (2, 0),
    "pytest": lambda v: True,
    "numpy": lambda v: True,
    "setuptools": lambda v: v >= (77, 0),
    "ray": lambda v: v >= (2, 9),
    "safetensors": lambda v: True,
    "matplotlib": lambda v: True,
    "torch": lambda v: v >= (2, 0),
}
bad = [name for name, ok in wants.items() if version(name) is None or not ok(version(name))]
if sys.version_info < (3, 10):
    bad.append(f"python >= 3.10 (have {sys.version.split()[0]})")
if bad:
    print("missing or wrong version: " + ", ".join(bad), file=sys.stderr)
    sys.exit(1)
PYCHECK
command -v cargo >/dev/null || die "cargo not found"
echo "Python: $("$PY" --version) in $VENV; $(cargo --version)"

# --- Rust: the default members (no Python needed).
section "cargo fmt --all -- --check"
cargo fmt --all -- --check

section "cargo clippy (workspace without the pyo3 crate)"
cargo clippy --workspace --exclude mvgrasp-py --all-targets -- -D warnings

section "cargo test --profile dist (workspace without the pyo3 crate)"
cargo test --workspace --exclude mvgrasp-py --profile dist

# --- The wheel. clippy on the pyo3 crate needs the interpreter; PYO3_BUILD_EXTENSION_MODULE
# matches what maturin sets. (maturin also passes its own PYO3_CONFIG_FILE, so pyo3's build
# script reruns between the two steps: a few seconds.)
export PYO3_PYTHON=$PY
export PYO3_BUILD_EXTENSION_MODULE=1

section "cargo clippy -p mvgrasp-py"
cargo clippy -p mvgrasp-py --all-targets -- -D warnings

section "maturin build (py/) -> target/wheels/mvgrasp/"
rm -rf "$WHEEL_DIR"
maturin build --manifest-path py/Cargo.toml --interpreter "$PY" --out "$WHEEL_DIR"
wheels=("$WHEEL_DIR"/mvgrasp-*.whl)
[[ ${#wheels[@]} -eq 1 && -f ${wheels[0]} ]] || die "expected one wheel in $WHEEL_DIR, found: ${wheels[*]}"
"$PY" -m pip install --quiet --force-reinstall --no-deps "${wheels[0]}"

section "pytest py/tests"
"$PY" -m pytest py/tests

# --- Training.
section "pip install -e training && pytest training/tests"
"$PY" -m pip install --quiet --no-build-isolation --no-deps -e training
"$PY" -m pytest training/tests

end_section
printf '\nAll checks and tests passed in %ds.\n' "$(($(date +%s) - SCRIPT_START))"
