"""Frame rate of the viewer's replay in headless Chromium, in real time (no virtual
time): starts `twinloop view ROBOT CSV`, opens the page through the DevTools
protocol with `?bench=S` (play S seconds at 1x from the start), and reads the
page's own measurement (requestAnimationFrame intervals) and its load time.

    python3 crates/twinloop-view/bench/make_replay.py /tmp/replay60.csv
    python3 crates/twinloop-view/bench/replay_fps.py target/release/twinloop builtin:km20 /tmp/replay60.csv

Needs chromium and the `websockets` Python package.
"""
import asyncio
import json
import re
import subprocess
import sys
import tempfile
import time

import websockets

import os


def chromium_cpu_s():
    """CPU seconds used so far by every chromium process (Linux /proc; 0 elsewhere):
    with the frames drawn, the browser's CPU per frame, which a shared machine's load
    disturbs less than the frame rate."""
    total = 0
    if not os.path.isdir("/proc"):
        return 0.0
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            if b"chromium" not in open("/proc/%s/cmdline" % pid, "rb").read().split(b"\0")[0]:
                continue
            f = open("/proc/%s/stat" % pid).read().rsplit(")", 1)[1].split()
            total += int(f[11]) + int(f[12])
        except (OSError, IndexError):
            continue
    return total / os.sysconf("SC_CLK_TCK")


WINDOW = os.environ.get("WINDOW", "1280,800")

CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
                  "--disable-background-networking", "--disable-component-update", "--disable-sync",
                  "--no-first-run", "--window-size=" + WINDOW, "--remote-debugging-port=0"]


async def run(ws_url, page_url, seconds):
    async with websockets.connect(ws_url, max_size=None) as ws:
        n = 0

        async def call(method, params=None, session=None):
            nonlocal n
            n += 1
            msg = {"id": n, "method": method, "params": params or {}}
            if session:
                msg["sessionId"] = session
            await ws.send(json.dumps(msg))
            while True:
                r = json.loads(await ws.recv())
                if r.get("id") == n:
                    return r.get("result", r)

        target = await call("Target.createTarget", {"url": "about:blank"})
        session = (await call("Target.attachToTarget", {"targetId": target["targetId"], "flatten": True}))["sessionId"]
        t0 = time.time()
        await call("Page.navigate", {"url": page_url}, session)
        deadline = time.time() + seconds + 120
        start = None
        while time.time() < deadline:
            r = await call("Runtime.evaluate", {"expression": "JSON.stringify(window.twinloop || null)", "returnByValue": True}, session)
            status = json.loads(r["result"].get("value") or "null")
            if status and status.get("ready") and start is None:
                start = (chromium_cpu_s(), status["frame"])
            if status and status.get("bench"):
                if start and status["frame"] > start[1]:
                    status["bench"]["cpu_per_frame_ms"] = 1e3 * (chromium_cpu_s() - start[0]) / (status["frame"] - start[1])
                return status
            if status and status.get("errors"):
                raise SystemExit("page errors: %s" % status["errors"])
            await asyncio.sleep(0.5)
        raise SystemExit("no result in time")


def main():
    binary, robot, csv = sys.argv[1:4]
    seconds = float(sys.argv[4]) if len(sys.argv) > 4 else 10
    view = subprocess.Popen([binary, "view", robot, csv], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    url = view.stdout.readline().strip()
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        chrome = subprocess.Popen(["chromium", *CHROMIUM_FLAGS, "--user-data-dir=" + profile],
                                  stderr=subprocess.PIPE, text=True)
        try:
            for line in chrome.stderr:
                m = re.search(r"DevTools listening on (ws://\S+)", line)
                if m:
                    break
            status = asyncio.run(run(m.group(1), url + "?bench=%g" % seconds + os.environ.get("QUERY", ""), seconds))
        finally:
            chrome.terminate()
            chrome.wait()
            view.terminate()
    print(json.dumps(status["bench"]))
    b = status["bench"]
    print("load (page start to first frame): %.0f ms" % status.get("load_ms", float("nan")))
    print("replay: %d frames, median %.2f ms, p95 %.2f ms, %.1f fps; page work per frame median %.2f ms (of which render() %.2f ms); "
          "chromium CPU per frame %.1f ms; load %.1f" % (b["frames"], b["median_ms"], b["p95_ms"], b["fps"], b["work_median_ms"],
                                                        b["render_median_ms"], b.get("cpu_per_frame_ms", float("nan")), os.getloadavg()[0]))


if __name__ == "__main__":
    main()
