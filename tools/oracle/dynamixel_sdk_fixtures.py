#!/usr/bin/env python3
"""Instruction packets built by the official ROBOTIS DynamixelSDK (PyPI `dynamixel-sdk`),
written as fixtures that a pure-Rust test compares twinloop's client against byte for byte.

    pip install dynamixel-sdk==4.1.0
    python3 tools/oracle/dynamixel_sdk_fixtures.py \
        > crates/twinloop-link/tests/data/sdk_packets.jsonl

Each output line is one JSON object: the request in twinloop's terms ("op" and its arguments)
and "wire", the bytes the SDK put on the port for it (hex). Nothing is sent anywhere: the SDK
writes into a port object that only records. The cases include values holding FF FF FD, both
protocols and every group instruction the SDK offers.

SDK 4.1.0 does not stuff the packets it sends: Protocol2PacketHandler.txPacket calls
addStuffing(txpacket) and drops its result, and addStuffing builds a new list whenever it
inserts a byte. Those packets keep FF FF FD unstuffed with the unstuffed LENGTH; the Rust test
checks them by content (a servo un-stuffs only FF FF FD FD, so it still reads them right).
"""

import json
import sys

import dynamixel_sdk as sdk


class RecordingPort:
    """Enough of PortHandler for the SDK's tx paths; reads return nothing at once."""

    def __init__(self):
        self.is_using = False
        self.written = []
        self.baudrate = 1000000

    def clearPort(self):
        pass

    def writePort(self, packet):
        self.written.append(bytes(packet))
        return len(packet)

    def readPort(self, length):
        return b""

    def getBytesAvailable(self):
        return 0

    def setPacketTimeout(self, packet_length):
        pass

    def setPacketTimeoutMillis(self, msec):
        pass

    def isPacketTimeout(self):
        return True

    def getBaudRate(self):
        return self.baudrate


def record(out, protocol, op, call, **args):
    port = RecordingPort()
    ph = sdk.PacketHandler(float(protocol))
    try:
        call(port, ph)
    except TypeError as e:  # SDK 4.1.0 bug paths are reported, not hidden
        print(f"SDK raised for {op}: {e}", file=sys.stderr)
        return
    if not port.written:
        print(f"SDK wrote nothing for {op} {args}", file=sys.stderr)
        return
    obj = {"protocol": protocol, "op": op}
    obj.update(args)
    obj["wire"] = port.written[0].hex(" ").upper()
    out.append(obj)


def le(value, size):
    return list((value & ((1 << (8 * size)) - 1)).to_bytes(size, "little"))


def main():
    out = []
    stuffed = le(-131073, 4)  # FF FF FD FF
    for p in (1, 2):
        for dxl_id in (1, 7, 200):
            record(out, p, "ping", lambda port, ph, i=dxl_id: ph.ping(port, i), id=dxl_id)
        for dxl_id, addr, n in ((1, 36, 2), (3, 43, 1), (5, 0, 49)) if p == 1 else (
                (1, 132, 4), (2, 126, 10), (9, 0, 147), (252, 578, 2)):
            record(out, p, "read", lambda port, ph, i=dxl_id, a=addr, k=n: ph.readTx(port, i, a, k),
                   id=dxl_id, address=addr, len=n)
        writes = [(1, 30, le(512, 2)), (2, 24, [1]), (254, 3, [1]), (4, 30, [0xFF, 0x03])] if p == 1 else [
            (1, 116, le(512, 4)), (1, 20, stuffed), (2, 64, [1]), (254, 65, [1]),
            (3, 116, [0xFF, 0xFF, 0xFD, 0xFF]), (4, 168, [0x00, 0xFF, 0xFF, 0xFD, 0x01, 0xFF, 0xFF, 0xFD]),
            (5, 600, le(1000, 2))]
        for dxl_id, addr, data in writes:
            record(out, p, "write",
                   lambda port, ph, i=dxl_id, a=addr, d=data: ph.writeTxOnly(port, i, a, len(d), d),
                   id=dxl_id, address=addr, data=data)
            record(out, p, "reg_write",
                   lambda port, ph, i=dxl_id, a=addr, d=data: ph.regWriteTxOnly(port, i, a, len(d), d),
                   id=dxl_id, address=addr, data=data)
        for dxl_id in (1, 254):
            record(out, p, "action", lambda port, ph, i=dxl_id: ph.action(port, i), id=dxl_id)
        if p == 2:
            record(out, p, "reboot", lambda port, ph: ph.reboot(port, 6), id=6)
            record(out, p, "clear", lambda port, ph: ph.clearMultiTurn(port, 6), id=6)
            for option in (0xFF, 0x01, 0x02):
                record(out, p, "factory_reset",
                       lambda port, ph, o=option: ph.factoryReset(port, 2, o), id=2, option=option)
        else:
            record(out, p, "factory_reset", lambda port, ph: ph.factoryReset(port, 2), id=2, option=0)

        # SYNC_WRITE through GroupSyncWrite.
        addr, n = (30, 2) if p == 1 else (116, 4)
        items = [(1, le(100, n)), (2, le(3000 if p == 2 else 1000, n)), (3, (stuffed if p == 2 else [0xFF, 0xFF]))]

        def sync_write(port, ph, items=items, addr=addr, n=n):
            g = sdk.GroupSyncWrite(port, ph, addr, n)
            for i, d in items:
                g.addParam(i, bytes(d))
            g.txPacket()

        record(out, p, "sync_write", sync_write, address=addr, len=n,
               items=[{"id": i, "data": d} for i, d in items])

        if p == 2:
            for fast in (False, True):
                for a, n, ids in ((132, 4, [1, 2, 3]), (126, 10, list(range(1, 21)))):
                    def sync_read(port, ph, a=a, n=n, ids=ids, fast=fast):
                        g = sdk.GroupSyncRead(port, ph, a, n)
                        for i in ids:
                            g.addParam(i)
                        if fast:
                            g.fastSyncReadTxPacket()
                        else:
                            g.txPacket()
                    record(out, p, "fast_sync_read" if fast else "sync_read", sync_read,
                           address=a, len=n, ids=ids)
            bulk = [(1, 144, 2), (2, 146, 1), (3, 132, 4)]

            def bulk_read(port, ph):
                g = sdk.GroupBulkRead(port, ph)
                for i, a, n in bulk:
                    g.addParam(i, a, n)
                g.txPacket()

            record(out, p, "bulk_read", bulk_read, items=[{"id": i, "address": a, "len": n} for i, a, n in bulk])
            bw = [(1, 32, le(160, 2)), (2, 31, [80]), (3, 20, stuffed)]

            def bulk_write(port, ph):
                g = sdk.GroupBulkWrite(port, ph)
                for i, a, d in bw:
                    g.addParam(i, a, len(d), bytes(d))
                g.txPacket()

            record(out, p, "bulk_write", bulk_write, items=[{"id": i, "address": a, "data": d} for i, a, d in bw])
        else:
            # Protocol 1.0 BULK_READ. GroupBulkRead.txPacket() raises TypeError in SDK 4.1.0
            # (it passes fast_option to a 3-argument bulkReadTx; the Python SDK's Protocol 1.0 bulkReadTx), so the
            # packet handler is called the way GroupBulkRead builds its parameters.
            bulk = [(1, 30, 2), (2, 36, 2)]
            param = []
            for i, a, n in bulk:
                param.extend([n, i, a])
            record(out, p, "bulk_read", lambda port, ph: ph.bulkReadTx(port, param, len(param)),
                   items=[{"id": i, "address": a, "len": n} for i, a, n in bulk])
    for obj in out:
        print(json.dumps(obj))
    print(f"{len(out)} packets from dynamixel-sdk {getattr(sdk, '__version__', '4.1.0')}", file=sys.stderr)


if __name__ == "__main__":
    main()
