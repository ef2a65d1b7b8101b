#!/usr/bin/env python3
"""What the official ROBOTIS DynamixelSDK's example programs do (python/tests: protocol2_0
indirect_address.py, clear_multi_turn.py, factory_reset.py; protocol1_0 read_write.py,
sync_write.py, bulk_read.py on an X servo set to Protocol 1.0), done without a keyboard
through the SDK's own API (PyPI `dynamixel-sdk` 4.1.0) against a twinloop virtual bus.

    twinloop serve --map tools/oracle/sdk_examples_bus.toml --link /tmp/dxl &
    python3 tools/oracle/dynamixel_sdk_examples.py --port /tmp/dxl

The bus (sdk_examples_bus.toml), served at 1 Mbps: XM430-W350 ids 1 and 2, XL430-W250 id 3 on
Protocol 2.0, XM430-W350 ids 4 and 5 declared `protocol = 1` (Protocol Type 1), MX-28(2.0) id 6
on 2.0 (switched to 1.0 and back here), RX-28 id 11 on 1.0.

Prints PASS/FAIL per check and "N passed, M failed"; exits 1 if any failed (2 if the port cannot
be opened).
"""

import argparse
import sys
import time

import dynamixel_sdk as sdk
from dynamixel_sdk.robotis_def import (COMM_RX_TIMEOUT, COMM_SUCCESS, DXL_HIBYTE, DXL_HIWORD,
                                       DXL_LOBYTE, DXL_LOWORD)

from dynamixel_sdk_conformance import RESULTS, check, rx, signed32

# X series / MX(2.0) control table (EM-XM).
BAUD, RETURN_DELAY, OPERATING_MODE, PROTOCOL_TYPE = 8, 9, 11, 13
TORQUE, LED, GOAL, MOVING, PRESENT = 64, 65, 116, 122, 132
INDIRECT_ADDRESS_W, INDIRECT_ADDRESS_R, INDIRECT_DATA_W, INDIRECT_DATA_R = 168, 178, 224, 229


def le4(v):
    return [DXL_LOBYTE(DXL_LOWORD(v)), DXL_HIBYTE(DXL_LOWORD(v)), DXL_LOBYTE(DXL_HIWORD(v)),
            DXL_HIBYTE(DXL_HIWORD(v))]


def baud_registers(port, p1, p2):
    v, res, _ = p2.read1ByteTxRx(port, 1, BAUD)
    check("Baud Rate of XM430 id 1 on a 1 Mbps line = 3 (EM-XM: 3 is 1 Mbps)", res == COMM_SUCCESS and v == 3,
          f"{res} {v}")
    v, res, _ = p1.read1ByteTxRx(port, 11, 4)
    check("Baud Rate of RX-28 id 11 on a 1 Mbps line = 1 (EM-RX28: 2 Mbps / (1 + 1))",
          res == COMM_SUCCESS and v == 1, f"{res} {v}")
    v, res, _ = p1.read1ByteTxRx(port, 4, BAUD)
    check("Baud Rate of XM430 id 4 (on Protocol 1.0) = 3", res == COMM_SUCCESS and v == 3, f"{res} {v}")


def indirect_address(port, p2, dxl=1):
    """protocol2_0/indirect_address.py: LED + Goal Position written, Present Position + Moving read,
    through Indirect Data, with GroupSyncWrite / GroupSyncRead."""
    ok = p2.write1ByteTxRx(port, dxl, TORQUE, 0) == (COMM_SUCCESS, 0)
    for k, target in enumerate([GOAL, GOAL + 1, GOAL + 2, GOAL + 3, LED]):
        ok &= p2.write2ByteTxRx(port, dxl, INDIRECT_ADDRESS_W + 2 * k, target) == (COMM_SUCCESS, 0)
    for k, target in enumerate([PRESENT, PRESENT + 1, PRESENT + 2, PRESENT + 3, MOVING]):
        ok &= p2.write2ByteTxRx(port, dxl, INDIRECT_ADDRESS_R + 2 * k, target) == (COMM_SUCCESS, 0)
    check("indirect_address: the ten Indirect Address writes succeed (torque off)", ok)
    ok = p2.write1ByteTxRx(port, dxl, TORQUE, 1) == (COMM_SUCCESS, 0)
    res, err = p2.write2ByteTxRx(port, dxl, INDIRECT_ADDRESS_W, GOAL)
    check("indirect_address: Indirect Address with torque on -> access error 7", ok and res == COMM_SUCCESS
          and err == 7, f"{res} {err}")
    writer = sdk.GroupSyncWrite(port, p2, INDIRECT_DATA_W, 5)
    reader = sdk.GroupSyncRead(port, p2, INDIRECT_DATA_R, 5)
    reader.addParam(dxl)
    for goal, led in ((0, 0), (4095, 1)):
        writer.addParam(dxl, le4(goal) + [led])
        res = writer.txPacket()
        writer.clearParam()
        present, moving, deadline = None, None, time.time() + 5.0
        while time.time() < deadline:
            if reader.txRxPacket() != COMM_SUCCESS or not reader.isAvailable(dxl, INDIRECT_DATA_R, 4):
                break
            present = signed32(reader.getData(dxl, INDIRECT_DATA_R, 4))
            moving = reader.getData(dxl, INDIRECT_DATA_R + 4, 1)
            if abs(goal - present) <= 20:
                break
        direct, _, _ = p2.read4ByteTxRx(port, dxl, GOAL)
        led_now, _, _ = p2.read1ByteTxRx(port, dxl, LED)
        check(f"indirect_address: goal {goal} LED {led} via Indirect Data; present via Indirect Data reaches it",
              res == COMM_SUCCESS and direct == goal and led_now == led and present is not None
              and abs(goal - present) <= 20 and moving in (0, 1), f"{res} {direct} {led_now} {present} {moving}")
    p2.write1ByteTxRx(port, dxl, TORQUE, 0)


def clear_multi_turn(port, p2, dxl=2):
    """protocol2_0/clear_multi_turn.py: extended position mode, run towards 1048575, stop (goal =
    present), wait 0.3 s, CLEAR, Present Position is back within one turn."""
    ok = p2.write1ByteTxRx(port, dxl, OPERATING_MODE, 4) == (COMM_SUCCESS, 0)
    ok &= p2.write1ByteTxRx(port, dxl, TORQUE, 1) == (COMM_SUCCESS, 0)
    ok &= p2.write4ByteTxRx(port, dxl, GOAL, 1048575) == (COMM_SUCCESS, 0)
    present, deadline = 0, time.time() + 6.0
    while time.time() < deadline and present < 2048 + 4096 + 100:
        v, res, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
        present = signed32(v) if res == COMM_SUCCESS else present
    check("clear_multi_turn: extended mode, more than a turn run", ok and present > 2048 + 4096, present)
    res, err = p2.clearMultiTurn(port, dxl)
    check("clear_multi_turn: CLEAR while moving -> result fail 1 (EM-P2 Clear)", res == COMM_SUCCESS and err == 1,
          f"{res} {err}")
    v, _, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    p2.write4ByteTxRx(port, dxl, GOAL, v)
    time.sleep(0.3)
    before, _, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    before = signed32(before)
    res, err = p2.clearMultiTurn(port, dxl)
    after, res2, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    check("clear_multi_turn: stopped, CLEAR; Present Position = before mod 4096",
          res == COMM_SUCCESS and err == 0 and res2 == COMM_SUCCESS and 0 <= after < 4096
          and abs(after - before % 4096) <= 2, f"{res} {err} {before} -> {after}")
    time.sleep(0.3)
    held, _, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    check("clear_multi_turn: the servo holds where it is after CLEAR", abs(held - after) <= 2, f"{after} {held}")
    p2.write1ByteTxRx(port, dxl, TORQUE, 0)


def factory_reset(port, p2, dxl=3):
    """protocol2_0/factory_reset.py with option 0x01 (all but ID), then the baud number written back."""
    p2.write1ByteTxRx(port, dxl, RETURN_DELAY, 0)
    p2.write1ByteTxRx(port, dxl, TORQUE, 1)
    p2.write4ByteTxRx(port, dxl, GOAL, 3000)
    time.sleep(0.6)
    res, err = p2.factoryReset(port, dxl, 0x01)
    time.sleep(0.2)
    baud, res2, _ = p2.read1ByteTxRx(port, dxl, BAUD)
    delay, _, _ = p2.read1ByteTxRx(port, dxl, RETURN_DELAY)
    torque, _, _ = p2.read1ByteTxRx(port, dxl, TORQUE)
    check("factory_reset 0x01: success, id kept, Baud Rate 1 (57600) and Return Delay 250 again, torque off",
          res == COMM_SUCCESS and err == 0 and res2 == COMM_SUCCESS and baud == 1 and delay == 250 and torque == 0,
          f"{res} {err} {res2} {baud} {delay} {torque}")
    goal, _, _ = p2.read4ByteTxRx(port, dxl, GOAL)
    present, _, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    check("factory_reset: Goal Position = Present Position after the reboot (not 0)",
          abs(goal - present) <= 1 and abs(present - 3000) <= 2, f"{goal} {present}")
    p2.write1ByteTxRx(port, dxl, TORQUE, 1)
    time.sleep(0.3)
    still, _, _ = p2.read4ByteTxRx(port, dxl, PRESENT)
    check("factory_reset: torque on does not swing the joint", abs(still - present) <= 2, f"{present} {still}")
    p2.write1ByteTxRx(port, dxl, TORQUE, 0)
    res, err = p2.write1ByteTxRx(port, dxl, BAUD, 3)
    check("factory_reset: the baud number written back (3: 1 Mbps)", res == COMM_SUCCESS and err == 0, f"{res} {err}")


def protocol1_x_servos(port, p1, p2):
    """protocol1_0/read_write.py, sync_write.py and bulk_read.py: X servos (ids 4, 5) with Protocol Type 1,
    at the X addresses (64, 116, 132, 122)."""
    model, res, _ = p1.ping(port, 4)
    m2, res2, _ = p2.ping(port, 4)
    check("1.0 ping of XM430 id 4 (protocol = 1 in the mapping) = 1020; silent on 2.0",
          res == COMM_SUCCESS and model == 1020 and res2 == COMM_RX_TIMEOUT, f"{res} {model} {res2}")
    ok = p1.write1ByteTxRx(port, 4, TORQUE, 1) == (COMM_SUCCESS, 0)
    for goal in (10, 4000):
        res, err = p1.write2ByteTxRx(port, 4, GOAL, goal)
        present, deadline = None, time.time() + 5.0
        while time.time() < deadline:
            present, res2, _ = p1.read2ByteTxRx(port, 4, PRESENT)
            if res2 != COMM_SUCCESS or abs(goal - present) <= 20:
                break
        check(f"read_write (1.0): write2Byte goal {goal} at 116, read2Byte present at 132 reaches it",
              ok and res == COMM_SUCCESS and err == 0 and present is not None and abs(goal - present) <= 20,
              f"{res} {err} {present}")
    p1.write1ByteTxRx(port, 5, TORQUE, 1)
    writer = sdk.GroupSyncWrite(port, p1, GOAL, 4)
    for dxl in (4, 5):
        writer.addParam(dxl, le4(100))
    res = writer.txPacket()
    time.sleep(1.5)
    # SDK 4.1.0's GroupBulkRead breaks on 1.0 (see dynamixel_sdk_conformance.py): the BULK_READ it means.
    param = [4, 4, PRESENT, 1, 5, MOVING]
    res2 = p1.bulkReadTx(port, param, len(param))
    d4, r4, _ = p1.readRx(port, 4, 4)
    d5, r5, _ = p1.readRx(port, 5, 1)
    pos4 = signed32(d4[0] | d4[1] << 8 | d4[2] << 16 | d4[3] << 24) if r4 == COMM_SUCCESS else None
    check("sync_write + bulk_read (1.0): both X servos at 100; BULK_READ present (4 B) and moving (1 B)",
          res == COMM_SUCCESS and res2 == COMM_SUCCESS and r4 == COMM_SUCCESS and r5 == COMM_SUCCESS
          and abs(pos4 - 100) <= 20 and d5[0] in (0, 1), f"{res} {res2} {r4} {pos4} {r5}")
    for dxl in (4, 5):
        p1.write1ByteTxRx(port, dxl, TORQUE, 0)


def protocol1_errors(port, p1):
    """Protocol 1.0 status error bits from an X servo on 1.0 (EM-P1 Status Packet)."""
    res, err = p1.write1ByteTxRx(port, 4, TORQUE, 5)
    check("1.0 error (X on 1.0): torque 5 out of range -> range bit 0x08", res == COMM_SUCCESS and err == 0x08,
          f"{res} {err}")
    res, err = p1.write4ByteTxRx(port, 4, PRESENT, 0)
    check("1.0 error (X on 1.0): write Present Position -> range bit 0x08", res == COMM_SUCCESS and err == 0x08,
          f"{res} {err}")
    body = [4, 2, 0x10]
    port.clearPort()
    port.writePort(bytes([0xFF, 0xFF] + body + [(~sum(body)) & 0xFF]))
    pkt, res = rx(port, p1)
    check("1.0 error (X on 1.0): undefined instruction 0x10 -> instruction bit 0x40",
          res == COMM_SUCCESS and pkt[2] == 4 and pkt[4] == 0x40, f"{p1.getTxRxResult(res)} {pkt}")
    body = [4, 4, 0x02, PRESENT, 4]
    port.clearPort()
    port.writePort(bytes([0xFF, 0xFF] + body + [((~sum(body)) & 0xFF) ^ 0x0F]))
    pkt, res = rx(port, p1)
    check("1.0 error (X on 1.0): damaged checksum -> checksum bit 0x10",
          res == COMM_SUCCESS and pkt[2] == 4 and pkt[4] == 0x10, f"{p1.getTxRxResult(res)} {pkt}")


def protocol_type_switch(port, p1, p2, dxl=6):
    """Protocol Type(13) written at run time: 1 switches the MX-28(2.0) to 1.0, 2 back."""
    res, err = p2.write1ByteTxRx(port, dxl, PROTOCOL_TYPE, 1)
    _, r2, _ = p2.ping(port, dxl)
    model, r1, _ = p1.ping(port, dxl)
    check("Protocol Type 1 (written on 2.0, answered on 2.0): the servo then answers 1.0 only",
          res == COMM_SUCCESS and err == 0 and r2 == COMM_RX_TIMEOUT and r1 == COMM_SUCCESS and model == 30,
          f"{res} {err} {r2} {r1} {model}")
    res, err = p1.write1ByteTxRx(port, dxl, PROTOCOL_TYPE, 2)
    model, r2, _ = p2.ping(port, dxl)
    check("Protocol Type 2 (written on 1.0): back on 2.0", res == COMM_SUCCESS and err == 0 and r2 == COMM_SUCCESS
          and model == 30, f"{res} {err} {r2} {model}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--port", required=True, help="pty path printed by `twinloop serve`")
    ap.add_argument("--baud", type=int, default=1000000)
    args = ap.parse_args()
    port = sdk.PortHandler(args.port)
    if not port.openPort() or not port.setBaudRate(args.baud):
        print(f"cannot open {args.port}", file=sys.stderr)
        return 2
    p2 = sdk.PacketHandler(2.0)
    p1 = sdk.PacketHandler(1.0)
    baud_registers(port, p1, p2)
    indirect_address(port, p2)
    clear_multi_turn(port, p2)
    factory_reset(port, p2)
    protocol1_x_servos(port, p1, p2)
    protocol1_errors(port, p1)
    protocol_type_switch(port, p1, p2)
    port.closePort()
    failed = [n for n, ok in RESULTS if not ok]
    print(f"{len(RESULTS) - len(failed)} passed, {len(failed)} failed (SDK examples against twinloop serve)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
