#!/usr/bin/env bash
# Run every fuzz target for a fixed time (issue 17): a crash, a panic, a timeout or an
# out-of-memory in any target fails this script, and with it CI.
#
#   bash fuzz/run-ci.sh            # 15 s per target
#   FUZZ_SECONDS=300 bash fuzz/run-ci.sh decoder urdf
#
# Without cargo-fuzz: installing it costs CI 4.5 minutes on two cores, and all it adds
# here is the flags below. The targets are built with the same SanitizerCoverage flags
# cargo-fuzz passes (libFuzzer's inline 8-bit counters, the PC table and compare
# tracing), `--cfg fuzzing`, debug assertions and overflow checks. None of them is a
# `-Z` flag, so the machine's own toolchain builds them (FUZZ_TOOLCHAIN=nightly picks
# another: the only thing nightly would add is a sanitizer).
# No AddressSanitizer: the fuzzed code (twinloop-link's decoder and mapping,
# twinloop-description, twinloop-dynamics) is safe Rust, so ASan would double the build
# and halve the executions per second to find nothing a panic does not already show.
# `--target` keeps the flags off build scripts and proc macros (serde_derive).
# Measured: the cold build 198 CPU-seconds (about 2 min on two free cores) plus the
# runs, 4 x 15 s: under 4 min; details in docs/architecture.md ("Layers", on fuzz/).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"

seconds=${FUZZ_SECONDS:-15}
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(decoder urdf mjcf mapping)
toolchain=()
[ -n "${FUZZ_TOOLCHAIN:-}" ] && toolchain=("+$FUZZ_TOOLCHAIN")
host=$(rustc "${toolchain[@]}" -vV | sed -n 's/^host: //p')

export RUSTFLAGS="-Cpasses=sancov-module \
 -Cllvm-args=-sanitizer-coverage-level=4 \
 -Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
 -Cllvm-args=-sanitizer-coverage-pc-table \
 -Cllvm-args=-sanitizer-coverage-trace-compares \
 --cfg fuzzing -Cdebug-assertions -Coverflow-checks"

start=$(date +%s)
cargo "${toolchain[@]}" build --locked --profile fuzz --target "$host" \
    $(printf -- '--bin %s ' "${targets[@]}")
echo "fuzz: built ${targets[*]} in $(($(date +%s) - start)) s"

bin="${CARGO_TARGET_DIR:-target}/$host/fuzz"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for t in "${targets[@]}"; do
    # A seed corpus of real inputs, so that the time goes into their neighbourhood
    # rather than into rediscovering XML from nothing.
    corpus="$work/$t"
    mkdir -p "$corpus"
    case $t in
        urdf) find ../models -name '*.urdf' -size -400k -exec cp {} "$corpus" \; ;;
        mjcf) find ../models -name '*.xml' -size -400k -exec cp {} "$corpus" \; ;;
        mapping) cp ../crates/twinloop-link/src/mappings/*.toml "$corpus" ;;
        decoder) cp seeds/decoder/* "$corpus" ;;
    esac
    echo "fuzz: $t for $seconds s from $(ls "$corpus" | wc -l) seeds"
    # -timeout: one input taking longer than 10 s is a hang and fails the run.
    "$bin/$t" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="$work/crash-$t-" -print_final_stats=1 2>"$work/$t.log" || {
        tail -n 40 "$work/$t.log"
        for a in "$work"/crash-"$t"-*; do
            [ -e "$a" ] && echo "fuzz: $t failed on $a (base64): $(base64 -w0 "$a")"
        done
        exit 1
    }
    grep -E '^stat::number_of_executed_units|^stat::peak_rss_mb' "$work/$t.log" |
        sed "s/^/fuzz: $t /"
done
echo "fuzz: all ${#targets[@]} targets ran ${seconds} s each without a crash"
