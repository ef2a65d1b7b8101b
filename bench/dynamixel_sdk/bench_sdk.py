#!/usr/bin/env python3
"""The official ROBOTIS Python SDK (PyPI `dynamixel-sdk`) timed on the same transactions as
`twinloop bench link --port`, against the same served robot:

    twinloop serve --map builtin:op3 --no-timing --link /tmp/op3 &
    python3 bench/dynamixel_sdk/bench_sdk.py --port /tmp/op3 --json

Cases (names match twinloop's): READ of 4 bytes from one servo; SYNC_READ and FAST_SYNC_READ of
4 bytes from servos 1..N; a control cycle (GroupSyncWrite of N goals + fast sync read of 10 bytes
from N servos). Median over batches of the time per transaction, microseconds, plus this thread's
CPU time per transaction.

Then the same cases again with the replies replayed from memory ("replay: ..."): each request's
reply is recorded once over the pty, and a port object that hands it back at once stands in for
the pty. What is left is the SDK's own cost per transaction, as `twinloop bench link` measures
twinloop's.
"""

import argparse
import json
import sys
import time

import dynamixel_sdk as sdk
from dynamixel_sdk.robotis_def import COMM_SUCCESS


def median_us(seconds, batch, f):
    """Median over batches of the wall time per call, and the mean CPU time of this thread
    per call (time.thread_time), both in us."""
    for _ in range(min(batch, 50)):
        f()
    samples = []
    start = time.perf_counter()
    cpu0 = time.thread_time()
    while len(samples) < 7 or (time.perf_counter() - start < seconds and len(samples) < 10000):
        t = time.perf_counter()
        for _ in range(batch):
            f()
        samples.append((time.perf_counter() - t) * 1e6 / batch)
    cpu = (time.thread_time() - cpu0) * 1e6 / (len(samples) * batch)
    samples.sort()
    return samples[len(samples) // 2], cpu


class RecordingPort:
    """Wraps the real port: remembers the reply bytes that followed each request."""

    def __init__(self, port):
        self.port = port
        self.replies = {}
        self.last = None

    def __getattr__(self, name):
        return getattr(self.port, name)

    @property
    def is_using(self):
        return self.port.is_using

    @is_using.setter
    def is_using(self, v):
        self.port.is_using = v

    def writePort(self, packet):
        self.last = bytes(packet)
        self.replies.setdefault(self.last, b"")
        return self.port.writePort(packet)

    def readPort(self, length):
        data = self.port.readPort(length)
        if data and self.last is not None:
            self.replies[self.last] += bytes(data)
        return data


class ReplayPort:
    """Hands back the recorded reply of each request at once; no pty, no server."""

    def __init__(self, replies):
        self.replies = replies
        self.buf = b""
        self.is_using = False
        self.baudrate = 1000000

    def clearPort(self):
        self.buf = b""

    def writePort(self, packet):
        self.buf = self.replies[bytes(packet)]
        return len(packet)

    def readPort(self, length):
        data, self.buf = self.buf[:length], self.buf[length:]
        return data

    def getBytesAvailable(self):
        return len(self.buf)

    def setPacketTimeout(self, packet_length):
        pass

    def setPacketTimeoutMillis(self, msec):
        pass

    def isPacketTimeout(self):
        return not self.buf

    def getBaudRate(self):
        return self.baudrate


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--port", required=True)
    ap.add_argument("--servos", type=int, default=20)
    ap.add_argument("--seconds", type=float, default=1.0)
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args()
    real = sdk.PortHandler(a.port)
    if not real.openPort() or not real.setBaudRate(1000000):
        print(f"cannot open {a.port}", file=sys.stderr)
        return 2
    cases = []
    recorder = RecordingPort(real)
    run_cases(recorder, a, "pty", cases)
    real.closePort()
    run_cases(ReplayPort(recorder.replies), a, "replay", cases)
    if FAILURES:
        print(f"{len(FAILURES)} transactions failed: {sorted(set(FAILURES))}", file=sys.stderr)
        return 1
    if a.json:
        print(json.dumps({"sdk": f"dynamixel-sdk {getattr(sdk, '__version__', '4.1.0')}", "cases": cases}, indent=1))
    else:
        for c in cases:
            print(f"{c['name']:<55} {c['median_us']:10.1f} us {c['cpu_us']:10.1f} us cpu {c['per_second']:10.0f} /s")
    return 0


FAILURES = []


def run_cases(port, a, label, cases):
    ph = sdk.PacketHandler(2.0)
    failures = FAILURES
    n = a.servos
    ids = list(range(1, n + 1))
    failures = []

    def read():
        _, res, _ = ph.read4ByteTxRx(port, 1, 132)
        if res != COMM_SUCCESS:
            failures.append("read")

    sync = sdk.GroupSyncRead(port, ph, 132, 4)
    for i in ids:
        sync.addParam(i)

    def sync_read():
        if sync.txRxPacket() != COMM_SUCCESS:
            failures.append("sync")

    def fast_sync_read():
        if sync.fastSyncRead() != COMM_SUCCESS:
            failures.append("fast")

    goals = sdk.GroupSyncWrite(port, ph, 116, 4)
    for i in ids:
        goals.addParam(i, (2048).to_bytes(4, "little"))
    wide = sdk.GroupSyncRead(port, ph, 126, 10)
    for i in ids:
        wide.addParam(i)

    def cycle():
        goals.txPacket()
        if wide.fastSyncRead() != COMM_SUCCESS:
            failures.append("cycle")

    for name, batch, f in (
        (f"{label}: READ 4 B (one servo)", 50, read),
        (f"{label}: SYNC_READ 4 B x {n}", 20, sync_read),
        (f"{label}: FAST_SYNC_READ 4 B x {n}", 20, fast_sync_read),
        (f"{label}: cycle SYNC_WRITE + FAST_SYNC_READ 10 B x {n}", 20, cycle),
    ):
        us, cpu = median_us(a.seconds, batch, f)
        cases.append({"name": name, "median_us": us, "cpu_us": cpu, "per_second": 1e6 / us})


if __name__ == "__main__":
    sys.exit(main())
