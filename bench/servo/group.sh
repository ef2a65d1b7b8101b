#!/bin/sh
# Twenty RX-28 benches of one truth but for friction_base (0.8-1.4 times, one value
# per servo), each logged once over its own pty by `experiment servo` (five at a
# time), then fitted together by one `identify servo` with ID=LOG.csv: the time of
# the whole comparison (each alone, all shared, the chosen mixed fit) on two threads.
set -e
here=$(cd "$(dirname "$0")" && pwd)
tw=${TWINLOOP:-twinloop}
work=${WORK:-$(mktemp -d)}
cd "$work"
"$tw" identify servo --defaults RX-28 --out base.toml
python3 - <<'PY'
import re
base = open("base.toml").read()
fb = float(re.search(r"^friction_base = (\S+)", base, re.M).group(1))
for k in range(20):
    f = 0.8 + 0.6 * k / 19
    open(f"truth-{k + 1}.toml", "w").write(
        re.sub(r"^friction_base = \S+", f"friction_base = {fb * f!r}", base, flags=re.M))
PY
for batch in 1 6 11 16; do
    servers=""
    runs=""
    for k in $(seq $batch $((batch + 4))); do
        "$tw" serve --bench RX-28 --load "$here/load.toml" --servo-params truth-$k.toml --link "$work/bus-$k" >/dev/null 2>&1 &
        servers="$servers $!"
    done
    sleep 1
    for k in $(seq $batch $((batch + 4))); do
        "$tw" experiment servo --port "$work/bus-$k" --timeout-ms 100 --retries 5 --id 1 --load "$here/load.toml" --out log-$k.csv &
        runs="$runs $!"
    done
    wait $runs
    kill $servers
done
args=""
for k in $(seq 1 20); do args="$args --data $k=log-$k.csv"; done
uptime
/usr/bin/time -f "wall %e s, CPU %U s user + %S s system" "$tw" identify servo $args --load "$here/load.toml" --threads 2 --out fits --json group.json
uptime
