#!/bin/sh
# The known-truth sweep of servo identification over ptys (issue 30 item 9;
# docs/servo-models.md, "Honest deviations"): for each servo type and seed a hidden
# random truth (crates/twinloop-actuator/examples/servo_sweep.rs: every m1 parameter
# times 0.7-1.3, the voltage times 0.9-1.1) served by `serve --bench`, two
# `experiment servo` logs, `identify servo --data a.csv --holdout b.csv --json`, and
# every reported number checked: within max(5 %, 3 sd) of the truth, or not
# determined with the truth in its interval.
#   SEEDS="1 2 3" TYPES="RX-28 XM430-W350" FACTOR=4 bench/servo/honest_sweep.sh
set -e
tw=${TWINLOOP:-twinloop}
sweep=${SWEEP:-servo_sweep}
work=${WORK:-$(mktemp -d)}
factor=${FACTOR:-4}
cd "$work"
failed=0
for servo in ${TYPES:-RX-28 RX-64 MX-64(2.0) XM430-W350}; do
    tag=$(echo "$servo" | tr -d '().')
    "$sweep" load "$servo" "load-$tag.toml"
    for seed in ${SEEDS:-1 2 3}; do
        base="$tag-$seed"
        "$sweep" truth "$servo" "$seed" "$base-truth.toml"
        "$tw" serve --bench "$servo" --load "load-$tag.toml" --servo-params "$base-truth.toml" \
            --realtime-factor "$factor" --link "$work/$base-bus" >/dev/null 2>&1 &
        server=$!
        sleep 1
        for part in a b; do
            "$tw" experiment servo --port "$work/$base-bus" --realtime-factor "$factor" \
                --timeout-ms 100 --retries 5 --id 1 --load "load-$tag.toml" --out "$base-$part.csv" \
                >/dev/null 2>&1
        done
        kill "$server"
        "$tw" identify servo --data "$base-a.csv" --holdout "$base-b.csv" --load "load-$tag.toml" \
            --model m1 --json "$base.json" >"$base.txt"
        echo "$servo seed $seed: $(grep -o 'held out [0-9.]* mrad RMS' "$base.txt")"
        "$sweep" check "$base-truth.toml" "$base.json" || failed=$((failed + 1))
    done
done
echo "cases failing: $failed (files in $work)"
[ "$failed" -eq 0 ]
