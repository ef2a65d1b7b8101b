#!/bin/sh
# Record two XM430-W350 bench logs over a pty and time twinloop's fit against SciPy's.
set -e
here=$(cd "$(dirname "$0")" && pwd)
tw=${TWINLOOP:-twinloop}
work=$(mktemp -d)
cd "$work"
"$tw" serve --bench XM430-W350 --load "$here/load.toml" --servo-params "$here/truth.toml" --link "$work/bus" >/dev/null 2>&1 &
server=$!
trap 'kill $server 2>/dev/null; rm -rf "$work"' EXIT
sleep 1
"$tw" experiment servo --port "$work/bus" --timeout-ms 50 --id 1 --load "$here/load.toml" --out log1.csv
"$tw" experiment servo --port "$work/bus" --timeout-ms 50 --id 1 --load "$here/load.toml" --out log2.csv
kill $server
echo "twinloop:"
taskset -c 0 "$tw" identify servo --data log1.csv log2.csv --load "$here/load.toml" --json - | grep -E '"(seconds|heldout_rms_mrad)"'
echo "scipy:"
taskset -c 0 python3 "$here/scipy_fit.py" "$here/load.toml" log1.csv log2.csv
