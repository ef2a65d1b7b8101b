"""The live view against a 1 kHz source, in real time: a writer appends km20 rows
to a CSV at 1 kHz (flushed every millisecond, as `link record` does), `twinloop view
ROBOT --live CSV` follows it, and headless Chromium (DevTools protocol) shows it.
Reports the frames drawn per second and the lag (publish on the server to the
frame drawn in the page, same clock).

    python3 crates/twinloop-view/bench/live_lag.py target/release/twinloop 10
    SOURCE=simulate python3 crates/twinloop-view/bench/live_lag.py target/release/twinloop 10

SOURCE=simulate streams a km20 simulation at 1 kHz with `simulate --view` instead
(the run starts when the page connects and goes at real time).
"""
import asyncio
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import threading
import time

import websockets

from replay_fps import CHROMIUM_FLAGS

JOINTS = ["l_hip_yaw", "l_hip_roll", "l_hip_pitch", "l_knee", "l_ank_pitch", "l_ank_roll",
          "r_hip_yaw", "r_hip_roll", "r_hip_pitch", "r_knee", "r_ank_pitch", "r_ank_roll",
          "l_sho_pitch", "l_sho_roll", "l_elbow", "r_sho_pitch", "r_sho_roll", "r_elbow",
          "head_pan", "head_tilt"]


def writer(path, stop):
    with open(path, "w") as f:
        f.write(",".join(["t"] + ["q:" + j for j in JOINTS]) + "\n")
        f.flush()
        t0 = time.perf_counter()
        k = 0
        while not stop.is_set():
            t = k * 1e-3
            while time.perf_counter() - t0 < t:
                time.sleep(0.0002)
            f.write(",".join(["%.4f" % t] + ["%.5f" % (0.4 * math.sin(2 * math.pi * 0.5 * t + i)) for i in range(len(JOINTS))]) + "\n")
            f.flush()
            k += 1


async def measure(ws_url, page_url, seconds):
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

        async def status():
            r = await call("Runtime.evaluate", {"expression": "JSON.stringify(window.twinloop || null)", "returnByValue": True}, session)
            return json.loads(r["result"].get("value") or "null")

        target = await call("Target.createTarget", {"url": "about:blank"})
        session = (await call("Target.attachToTarget", {"targetId": target["targetId"], "flatten": True}))["sessionId"]
        await call("Page.navigate", {"url": page_url}, session)
        await asyncio.sleep(5)  # load, connect, warm up
        a, ta = await status(), time.time()
        await asyncio.sleep(seconds)
        b, tb = await status(), time.time()
        if b.get("errors"):
            raise SystemExit("page errors: %s" % b["errors"])
        dt = tb - ta
        return ((b["frame"] - a["frame"]) / dt, (b["live"]["frames"] - a["live"]["frames"]) / dt,
                (b["live"]["fresh"] - a["live"]["fresh"]) / dt, b["live"])


def main():
    binary = sys.argv[1]
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 10
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as tmp:
        csv = os.path.join(tmp, "run.csv")
        stop = threading.Event()
        w = threading.Thread(target=writer, args=(csv, stop))
        if os.environ.get("SOURCE") == "simulate":
            view = subprocess.Popen([binary, "simulate", "--robot", "builtin:km20", "--duration", str(seconds + 10),
                                     "--out", csv, "--view"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            url = view.stderr.readline().strip().removeprefix("live view: ")
        else:
            w.start()
            view = subprocess.Popen([binary, "view", "builtin:km20", "--live", csv], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
            url = view.stdout.readline().strip()
        chrome = subprocess.Popen(["chromium", *CHROMIUM_FLAGS, "--user-data-dir=" + os.path.join(tmp, "profile")], stderr=subprocess.PIPE, text=True)
        try:
            for line in chrome.stderr:
                m = re.search(r"DevTools listening on (ws://\S+)", line)
                if m:
                    break
            drawn, received, fresh, live = asyncio.run(measure(m.group(1), url + os.environ.get("QUERY", ""), seconds))
        finally:
            chrome.terminate()
            chrome.wait()
            view.terminate()
            stop.set()
            if w.is_alive():
                w.join()
    print("live: %.1f frames drawn/s, %.1f of them with a new state; %.1f states received/s; "
          "lag to the frame drawn: median %.1f ms, p95 %.1f, max %.1f; "
          "lag on arrival: median %.1f, p95 %.1f, max %.1f (last 600 states); load %.1f" % (
              drawn, fresh, received, live["lag_median_ms"], live["lag_p95_ms"], live["lag_max_ms"],
              live["recv_lag_median_ms"], live["recv_lag_p95_ms"], live["recv_lag_max_ms"], os.getloadavg()[0]))


if __name__ == "__main__":
    main()
