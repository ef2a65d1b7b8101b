#!/usr/bin/env bash
# Build the twinloop Python package and run its pytest suite (python/tests).
#
# Needs Rust, Python >= 3.9 with pip, and a C compiler. Installs the pinned build and
# test tools, builds the abi3 wheel with the `ci` profile (optimised, no LTO), installs
# it, builds the CLI (for the CLI/Python parity test) and runs pytest. Oracles that are
# missing fail their tests instead of skipping them (TWINLOOP_REQUIRE_ORACLES=1) unless
# the caller sets TWINLOOP_REQUIRE_ORACLES=0.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/.." && pwd)"
py="${PYTHON:-python3}"
target="${CARGO_TARGET_DIR:-$repo/target}"
export CARGO_TARGET_DIR="$target"

"$py" -m pip install --quiet --disable-pip-version-check --root-user-action=ignore \
    "maturin==1.16.0" "pytest==9.2.0" "numpy==2.3.5" "pin==4.1.0" "ray==2.52.0" "tqdm==4.70.1" \
    "yourdfpy==0.0.60" "urdf-parser-py==0.0.4" "example-robot-data==6.0.0" \
    "mcap==1.6.0" "mcap-ros2-support==0.6.0" "rosbags==0.11.9"

rm -f "$target"/wheels/twinloop-*.whl
"$py" -m maturin build --profile ci --manifest-path "$here/Cargo.toml" --interpreter "$py" --out "$target/wheels"
wheel="$(ls "$target"/wheels/twinloop-*.whl)"
"$py" -m pip install --quiet --disable-pip-version-check --root-user-action=ignore --force-reinstall --no-deps "$wheel"
# Then through its [ray] extra, as `pip install "twinloop[ray]"` does: pip resolves the
# extra's requirements against what is installed (the pinned ray above). pip only warns
# about an extra the package does not declare, so that warning fails the run.
extra_log="$("$py" -m pip install --disable-pip-version-check --root-user-action=ignore "${wheel}[ray]" 2>&1)" || {
    echo "$extra_log"; exit 1; }
if grep -qi "does not provide the extra" <<<"$extra_log"; then
    echo "$extra_log"; echo "the wheel has no [ray] extra" >&2; exit 1
fi

cargo build --quiet -p twinloop-cli --profile ci --manifest-path "$repo/Cargo.toml"

export TWINLOOP_REQUIRE_ORACLES="${TWINLOOP_REQUIRE_ORACLES:-1}"
cd "$repo"
exec "$py" -m pytest -q -p no:cacheprovider "$here/tests" "$@"
