#!/usr/bin/env bash
# Build the twinloop wheel (profile ci: optimised, no LTO) and install it.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${TWINLOOP_WHEEL_DIR:-$here/../target/wheels}"
rm -f "$out"/twinloop-*.whl
maturin build --profile ci -m "$here/Cargo.toml" -o "$out"
python3 -m pip install --force-reinstall --no-deps "$out"/twinloop-*.whl
