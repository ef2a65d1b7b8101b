#!/usr/bin/env python3
"""The official ROBOTIS DynamixelSDK (PyPI `dynamixel-sdk`) as a client of a twinloop virtual
robot: everything a user's SDK program does must work against `twinloop serve`.

    pip install dynamixel-sdk==4.1.0
    twinloop serve --map tools/oracle/sdk_bus.toml --link /tmp/dxl &
    python3 tools/oracle/dynamixel_sdk_conformance.py --port /tmp/dxl

The bus (sdk_bus.toml): XM430-W350 ids 1-3 and XL430-W250 id 4 on Protocol 2.0, RX-28 id 11,
RX-64 id 12 and MX-28 id 13 on Protocol 1.0, all on the same line. Checked: ping, broadcast
ping, read/write of 1, 2 and 4 bytes, reg-write + action, group sync write/read, fast sync
read, bulk read/write, fast bulk read, byte stuffing both ways (-131073 is FF FF FD FF), error
statuses (CRC, data range, data length, data limit, access; 1.0 checksum, range and angle
limit bits), reboot, clear, factory reset, Protocol 1.0 next to 2.0, and the SDK's own
1.0 limits (no sync read; its GroupBulkRead bug).

Prints PASS/FAIL per check and exits 1 if any check failed (2 if the port cannot be opened).
"""

import argparse
import sys
import time

import dynamixel_sdk as sdk
from dynamixel_sdk.robotis_def import (COMM_NOT_AVAILABLE, COMM_RX_TIMEOUT, COMM_SUCCESS,
                                       DXL_HIBYTE, DXL_LOBYTE)

RESULTS = []


def check(name, ok, detail=""):
    RESULTS.append((name, bool(ok)))
    print(("PASS " if ok else "FAIL ") + name + ("" if ok else f": {detail}"), flush=True)


def signed32(v):
    return v - (1 << 32) if v >= 1 << 31 else v


def u32(v):
    return v & 0xFFFFFFFF


def rx(port, ph):
    port.setPacketTimeout(64)
    if ph.getProtocolVersion() == 2.0:
        pkt, res = ph.rxPacket(port, False)
    else:
        pkt, res = ph.rxPacket(port)
    return pkt, res


def crc_packet(ph, body):
    """A 2.0 packet from header+id+len+inst+params with its CRC appended."""
    crc = ph.updateCRC(0, body, len(body))
    return bytes(body + [DXL_LOBYTE(crc), DXL_HIBYTE(crc)])


def protocol2(port, p2):
    # --- ping, broadcast ping ---------------------------------------------------------------
    model, res, err = p2.ping(port, 1)
    check("2.0 ping id 1 -> XM430-W350 (1020)", res == COMM_SUCCESS and err == 0 and model == 1020,
          f"{p2.getTxRxResult(res)} model={model} err={err}")
    model, res, err = p2.ping(port, 50)
    check("2.0 ping absent id 50 times out", res == COMM_RX_TIMEOUT, p2.getTxRxResult(res))
    found, res = p2.broadcastPing(port)
    check("2.0 broadcast ping finds exactly ids 1-4 with their models",
          res == COMM_SUCCESS and sorted(found) == [1, 2, 3, 4] and found[4][0] == 1060 and found[1][0] == 1020,
          f"{p2.getTxRxResult(res)} {found}")

    # --- read 1/2/4 bytes --------------------------------------------------------------------
    v, res, err = p2.read2ByteTxRx(port, 4, 0)
    check("2.0 read2Byte model number of id 4 = 1060", res == COMM_SUCCESS and v == 1060, f"{v} {res}")
    v, res, err = p2.read1ByteTxRx(port, 3, 7)
    check("2.0 read1Byte ID of id 3 = 3", res == COMM_SUCCESS and v == 3, f"{v} {res}")
    v, res, err = p2.read4ByteTxRx(port, 1, 132)
    check("2.0 read4Byte present position at rest = 2048", res == COMM_SUCCESS and v == 2048, f"{v} {res}")

    # --- write, then the servo moves ------------------------------------------------------------
    res, err = p2.write1ByteTxRx(port, 1, 64, 1)
    check("2.0 write1Byte torque enable", res == COMM_SUCCESS and err == 0, f"{res} {err}")
    res, err = p2.write4ByteTxRx(port, 1, 116, 2500)
    check("2.0 write4Byte goal position 2500", res == COMM_SUCCESS and err == 0, f"{res} {err}")
    time.sleep(0.8)
    v, res, err = p2.read4ByteTxRx(port, 1, 132)
    check("2.0 servo reached its goal (present position 2500 +-3)", res == COMM_SUCCESS and abs(v - 2500) <= 3, v)
    res, err = p2.write2ByteTxRx(port, 1, 84, 640)
    v, res2, _ = p2.read2ByteTxRx(port, 1, 84)
    check("2.0 write2Byte/read2Byte position P gain", res == COMM_SUCCESS and v == 640, f"{res} {v}")

    # --- reg write + action ------------------------------------------------------------------------
    res, err = p2.regWriteTxRx(port, 2, 65, 1, [1])
    led, _, _ = p2.read1ByteTxRx(port, 2, 65)
    reg, _, _ = p2.read1ByteTxRx(port, 2, 69)
    check("2.0 reg write staged (LED still 0, Registered Instruction 1)",
          res == COMM_SUCCESS and led == 0 and reg == 1, f"{res} led={led} reg={reg}")
    p2.action(port, sdk.BROADCAST_ID)
    time.sleep(0.01)
    led, _, _ = p2.read1ByteTxRx(port, 2, 65)
    reg, _, _ = p2.read1ByteTxRx(port, 2, 69)
    check("2.0 action executes it (LED 1, Registered 0)", led == 1 and reg == 0, f"led={led} reg={reg}")

    # --- group sync write / sync read / fast sync read -----------------------------------------------
    torque = sdk.GroupSyncWrite(port, p2, 64, 1)
    for i in (1, 2, 3, 4):
        torque.addParam(i, bytes([1]))
    res = torque.txPacket()
    goals = {1: 1800, 2: 2300, 3: 2600, 4: 1500}
    gw = sdk.GroupSyncWrite(port, p2, 116, 4)
    for i, g in goals.items():
        gw.addParam(i, bytes(u32(g).to_bytes(4, "little")))
    res2 = gw.txPacket()
    check("2.0 GroupSyncWrite torque and goals", res == COMM_SUCCESS and res2 == COMM_SUCCESS, f"{res} {res2}")
    time.sleep(1.0)
    gr = sdk.GroupSyncRead(port, p2, 132, 4)
    for i in goals:
        gr.addParam(i)
    res = gr.txRxPacket()
    got = {i: signed32(gr.getData(i, 132, 4)) for i in goals}
    check("2.0 GroupSyncRead present positions reach the goals (+-3)",
          res == COMM_SUCCESS and all(abs(got[i] - goals[i]) <= 3 for i in goals), f"{p2.getTxRxResult(res)} {got}")
    res = gr.fastSyncRead()
    fast = {i: signed32(gr.getData(i, 132, 4)) for i in goals}
    check("2.0 fast sync read agrees with sync read", res == COMM_SUCCESS and fast == got,
          f"{p2.getTxRxResult(res)} {fast} vs {got}")
    wide = sdk.GroupSyncRead(port, p2, 126, 10)
    for i in goals:
        wide.addParam(i)
    res = wide.fastSyncRead()
    pos = {i: signed32(wide.getData(i, 132, 4)) for i in goals}
    check("2.0 fast sync read of current/load + velocity + position (10 bytes x 4 servos)",
          res == COMM_SUCCESS and pos == got, f"{p2.getTxRxResult(res)} {pos}")

    # --- bulk read / bulk write / fast bulk read -------------------------------------------------
    bw = sdk.GroupBulkWrite(port, p2)
    bw.addParam(1, 65, 1, bytes([1]))
    bw.addParam(3, 84, 2, bytes([DXL_LOBYTE(700), DXL_HIBYTE(700)]))
    res = bw.txPacket()
    led, _, _ = p2.read1ByteTxRx(port, 1, 65)
    gain, _, _ = p2.read2ByteTxRx(port, 3, 84)
    check("2.0 GroupBulkWrite (LED of 1, P gain of 3)", res == COMM_SUCCESS and led == 1 and gain == 700,
          f"{res} led={led} gain={gain}")
    br = sdk.GroupBulkRead(port, p2)
    br.addParam(1, 144, 2)  # voltage
    br.addParam(2, 146, 1)  # temperature
    br.addParam(4, 126, 2)  # XL430 present load
    res = br.txRxPacket()
    volt, temp, load = br.getData(1, 144, 2), br.getData(2, 146, 1), br.getData(4, 126, 2)
    check("2.0 GroupBulkRead (12.0 V, 36 degC, load)", res == COMM_SUCCESS and volt == 120 and temp == 36,
          f"{p2.getTxRxResult(res)} {volt} {temp} {load}")
    res = br.fastBulkRead()
    check("2.0 fast bulk read agrees", res == COMM_SUCCESS and br.getData(1, 144, 2) == 120
          and br.getData(2, 146, 1) == 36, p2.getTxRxResult(res))

    # --- byte stuffing both ways ------------------------------------------------------------------
    p2.write1ByteTxRx(port, 3, 64, 0)
    res, err = p2.write4ByteTxRx(port, 3, 20, u32(-131073))
    v, res2, _ = p2.read4ByteTxRx(port, 3, 20)
    check("stuffing: homing offset -131073 (FF FF FD FF) written and read back",
          res == COMM_SUCCESS and err == 0 and res2 == COMM_SUCCESS and signed32(v) == -131073,
          f"{res} {err} {res2} {signed32(v)}")
    p2.write4ByteTxRx(port, 3, 20, u32(-131073 - 2600))
    v, res, _ = p2.read4ByteTxRx(port, 3, 132)
    check("stuffing: present position -131073 read (stuffed status)", res == COMM_SUCCESS and signed32(v) == -131073,
          f"{res} {signed32(v)}")
    gr2 = sdk.GroupSyncRead(port, p2, 132, 4)
    gr2.addParam(2)
    gr2.addParam(3)
    res = gr2.txRxPacket()
    check("stuffing: -131073 through GroupSyncRead", res == COMM_SUCCESS and signed32(gr2.getData(3, 132, 4)) == -131073,
          f"{p2.getTxRxResult(res)} {signed32(gr2.getData(3, 132, 4))}")
    res = gr2.fastSyncRead()
    check("stuffing: -131073 through fast sync read", res == COMM_SUCCESS and signed32(gr2.getData(3, 132, 4)) == -131073,
          f"{p2.getTxRxResult(res)} {signed32(gr2.getData(3, 132, 4))}")
    p2.write4ByteTxRx(port, 3, 20, 0)

    # --- error statuses ----------------------------------------------------------------------------
    res, err = p2.write1ByteTxRx(port, 2, 64, 5)
    check("error: data range (torque enable = 5) -> 0x04", res == COMM_SUCCESS and err & 0x7F == 4, f"{res} {err}")
    res, err = p2.write2ByteTxRx(port, 2, 116, 100)
    check("error: data length (2 bytes into 4-byte goal) -> 0x05", res == COMM_SUCCESS and err & 0x7F == 5, f"{res} {err}")
    res, err = p2.write4ByteTxRx(port, 2, 116, 5000)
    check("error: data limit (goal 5000 > max position limit) -> 0x06", res == COMM_SUCCESS and err & 0x7F == 6,
          f"{res} {err}")
    res, err = p2.write4ByteTxRx(port, 2, 132, 0)
    check("error: access (write present position) -> 0x07", res == COMM_SUCCESS and err & 0x7F == 7, f"{res} {err}")
    res, err = p2.write4ByteTxRx(port, 2, 48, 4000)
    check("error: access (EEPROM with torque on) -> 0x07", res == COMM_SUCCESS and err & 0x7F == 7, f"{res} {err}")
    body = [0xFF, 0xFF, 0xFD, 0x00, 2, 7, 0, 0x02, 132, 0, 4, 0]
    bad = bytearray(crc_packet(p2, body))
    bad[-1] ^= 0x55
    port.clearPort()
    port.writePort(bad)
    pkt, res = rx(port, p2)
    check("error: CRC (damaged READ) -> status 0x03 from id 2",
          res == COMM_SUCCESS and pkt[4] == 2 and pkt[8] & 0x7F == 3, f"{p2.getTxRxResult(res)} {pkt}")
    port.clearPort()
    port.writePort(crc_packet(p2, [0xFF, 0xFF, 0xFD, 0x00, 2, 3, 0, 0x05]))
    pkt, res = rx(port, p2)
    check("error: instruction (ACTION with nothing registered) -> 0x02",
          res == COMM_SUCCESS and pkt[8] & 0x7F == 2, f"{p2.getTxRxResult(res)} {pkt}")

    # --- clear, reboot, factory reset ------------------------------------------------------------
    res, err = p2.clearMultiTurn(port, 1)
    check("2.0 clear multi-turn at rest", res == COMM_SUCCESS and err == 0, f"{res} {err}")
    res, err = p2.reboot(port, 2)
    time.sleep(0.05)
    te, res2, _ = p2.read1ByteTxRx(port, 2, 64)
    check("2.0 reboot (torque off after)", res == COMM_SUCCESS and err == 0 and res2 == COMM_SUCCESS and te == 0,
          f"{res} {err} {res2} te={te}")
    p2.write1ByteTxRx(port, 4, 9, 0)
    res, err = p2.factoryReset(port, 4, 0x01)
    time.sleep(0.05)
    rdt, res2, _ = p2.read1ByteTxRx(port, 4, 9)
    check("2.0 factory reset keeping the id (return delay back to 250)",
          res == COMM_SUCCESS and res2 == COMM_SUCCESS and rdt == 250, f"{res} {res2} {rdt}")


def protocol1(port, p1, p2):
    model, res, err = p1.ping(port, 11)
    check("1.0 ping id 11 -> RX-28 (28)", res == COMM_SUCCESS and model == 28, f"{p1.getTxRxResult(res)} {model}")
    model, res, err = p1.ping(port, 13)
    check("1.0 ping id 13 -> MX-28 (29)", res == COMM_SUCCESS and model == 29, f"{p1.getTxRxResult(res)} {model}")
    found, res = p1.broadcastPing(port)
    check("1.0 broadcast ping is not available in the SDK", res == COMM_NOT_AVAILABLE, res)
    res, err = p1.write1ByteTxRx(port, 11, 24, 1)
    res2, err2 = p1.write2ByteTxRx(port, 11, 30, 700)
    time.sleep(1.0)
    v, res3, _ = p1.read2ByteTxRx(port, 11, 36)
    check("1.0 torque on, goal 700, present position reaches it (+-2)",
          res == COMM_SUCCESS and res2 == COMM_SUCCESS and res3 == COMM_SUCCESS and abs(v - 700) <= 2, f"{res} {res2} {v}")
    res, err = p1.regWriteTxRx(port, 12, 25, 1, [1])
    led, _, _ = p1.read1ByteTxRx(port, 12, 25)
    p1.action(port, sdk.BROADCAST_ID)
    time.sleep(0.01)
    led2, _, _ = p1.read1ByteTxRx(port, 12, 25)
    check("1.0 reg write + broadcast action", res == COMM_SUCCESS and led == 0 and led2 == 1, f"{res} {led} {led2}")
    gw = sdk.GroupSyncWrite(port, p1, 30, 2)
    for i, g in ((11, 400), (12, 600), (13, 3000)):
        gw.addParam(i, bytes([DXL_LOBYTE(g), DXL_HIBYTE(g)]))
    res = gw.txPacket()
    p1.write1ByteTxRx(port, 13, 24, 1)
    time.sleep(1.0)
    pos = [p1.read2ByteTxRx(port, i, 30)[0] for i in (11, 12, 13)]
    check("1.0 GroupSyncWrite goals", res == COMM_SUCCESS and pos == [400, 600, 3000], f"{res} {pos}")
    gr = sdk.GroupSyncRead(port, p1, 36, 2)
    check("1.0 GroupSyncRead is not available (no SYNC_READ in 1.0)", gr.addParam(11) is False
          and gr.txRxPacket() == COMM_NOT_AVAILABLE)
    # SDK 4.1.0 GroupBulkRead.txPacket passes 4 arguments to Protocol1PacketHandler.bulkReadTx,
    # which takes 3 (the Python SDK's Protocol 1.0 bulkReadTx): confirm, then do what it meant to do.
    br = sdk.GroupBulkRead(port, p1)
    br.addParam(13, 36, 2)
    br.addParam(11, 30, 2)
    try:
        br.txPacket()
        bug = False
    except TypeError:
        bug = True
    check("1.0 SDK GroupBulkRead raises TypeError (known SDK 4.1.0 bug)", bug)
    param = [2, 13, 36, 2, 11, 30]
    res = p1.bulkReadTx(port, param, len(param))
    d13, r13, _ = p1.readRx(port, 13, 2)
    d11, r11, _ = p1.readRx(port, 11, 2)
    mx_pos = d13[0] | d13[1] << 8 if r13 == COMM_SUCCESS else None
    check("1.0 BULK_READ (MX-28 answers; RX-28 has none and stays silent)",
          res == COMM_SUCCESS and r13 == COMM_SUCCESS and abs(mx_pos - 3000) <= 2 and r11 != COMM_SUCCESS,
          f"{res} {r13} {mx_pos} {r11}")
    res, err = p1.write2ByteTxRx(port, 11, 36, 0)
    check("1.0 error: write present position -> range bit 0x08", res == COMM_SUCCESS and err == 0x08, f"{res} {err}")
    p1.write2ByteTxRx(port, 11, 8, 800)
    res, err = p1.write2ByteTxRx(port, 11, 30, 900)
    check("1.0 error: goal beyond CCW angle limit -> angle limit bit 0x02", res == COMM_SUCCESS and err == 0x02,
          f"{res} {err}")
    body = [11, 4, 0x02, 36, 2]
    ck = (~sum(body)) & 0xFF
    port.clearPort()
    port.writePort(bytes([0xFF, 0xFF] + body + [ck ^ 0x0F]))
    pkt, res = rx(port, p1)
    check("1.0 error: damaged checksum -> checksum bit 0x10 from id 11",
          res == COMM_SUCCESS and pkt[2] == 11 and pkt[4] == 0x10, f"{p1.getTxRxResult(res)} {pkt}")
    res, err = p1.factoryReset(port, 12)
    check("1.0 factory reset (id becomes 1: RX resets everything)", res == COMM_SUCCESS
          and p1.ping(port, 1)[1] == COMM_SUCCESS and p1.ping(port, 12)[1] != COMM_SUCCESS, res)
    model, res, _ = p2.ping(port, 1)
    check("2.0 servos still answer after 1.0 traffic on the same line", res == COMM_SUCCESS and model == 1020,
          f"{res} {model}")


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
    protocol2(port, p2)
    protocol1(port, p1, p2)
    port.closePort()
    failed = [n for n, ok in RESULTS if not ok]
    print(f"{len(RESULTS) - len(failed)} passed, {len(failed)} failed (dynamixel-sdk against twinloop serve)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
