#!/bin/sh
# twinloop's Dynamixel client vs the official Python SDK on the same virtual robot, same pty.
#   pip install dynamixel-sdk==4.1.0     (or PYTHON=path/to/python with it)
#   sh bench/dynamixel_sdk/run.sh        (from the repository root)
set -eu
PYTHON=${PYTHON:-python3}
SECONDS_PER_CASE=${SECONDS_PER_CASE:-2}
OUT=${OUT:-target/bench-dynamixel}
mkdir -p "$OUT"
cargo build --release -p twinloop-cli
BIN=target/release/twinloop
# Stand-in servos (no physics): the benchmark times the protocol path only.
$BIN serve --map builtin:op3 --servo-model ideal --no-timing --spin-us "${SERVER_SPIN_US:-0}" > "$OUT/pty.txt" 2> "$OUT/serve.log" &
SERVER=$!
trap 'kill -INT $SERVER 2>/dev/null || true' EXIT
sleep 0.5
PTY=$(head -n 1 "$OUT/pty.txt")
# Alternate the two clients for ROUNDS rounds: on a shared machine the load drifts, and the
# comparison takes, per case, the median over rounds of each side's median.
ROUNDS=${ROUNDS:-3}
ours=""
theirs=""
i=1
while [ "$i" -le "$ROUNDS" ]; do
    $BIN bench link --port "$PTY" --seconds "$SECONDS_PER_CASE" --spin-us "${CLIENT_SPIN_US:-0}" --json - > "$OUT/twinloop-$i.json"
    "$PYTHON" bench/dynamixel_sdk/bench_sdk.py --port "$PTY" --seconds "$SECONDS_PER_CASE" --json > "$OUT/sdk-$i.json"
    ours="$ours $OUT/twinloop-$i.json"
    theirs="$theirs $OUT/sdk-$i.json"
    i=$((i + 1))
done
"$PYTHON" bench/dynamixel_sdk/compare.py --ours $ours --sdk $theirs
