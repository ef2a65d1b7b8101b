"""The frame-rate floor of headless Chromium with software WebGL on this machine:
floor.html (an empty WebGL canvas cleared every frame, or no canvas) measured as
replay_fps.py measures the viewer.

    WINDOW=640,480 python3 crates/twinloop-view/bench/floor_fps.py 'gl=1&aa=1' 10
"""
import asyncio
import os
import re
import subprocess
import sys
import tempfile

from replay_fps import CHROMIUM_FLAGS, run


def main():
    query = sys.argv[1] if len(sys.argv) > 1 else "gl=1&aa=1"
    seconds = float(sys.argv[2]) if len(sys.argv) > 2 else 10
    page = "file://" + os.path.join(os.path.dirname(os.path.abspath(__file__)), "floor.html")
    with tempfile.TemporaryDirectory(ignore_cleanup_errors=True) as profile:
        chrome = subprocess.Popen(["chromium", *CHROMIUM_FLAGS, "--user-data-dir=" + profile],
                                  stderr=subprocess.PIPE, text=True)
        try:
            for line in chrome.stderr:
                m = re.search(r"DevTools listening on (ws://\S+)", line)
                if m:
                    break
            status = asyncio.run(run(m.group(1), "%s?%s&bench=%g" % (page, query, seconds), seconds))
        finally:
            chrome.terminate()
            chrome.wait()
    b = status["bench"]
    print("floor %s: %d frames, median %.2f ms, p95 %.2f ms, %.1f fps; load %.1f" % (query, b["frames"], b["median_ms"], b["p95_ms"], b["fps"], os.getloadavg()[0]))


if __name__ == "__main__":
    main()
