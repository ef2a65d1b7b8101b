#!/usr/bin/env python3
"""The reference Python reader on a JointState log: `mcap_ros2.reader.read_ros2_messages`
(mcap 1.6 + mcap-ros2-support 0.6), every message decoded and its stamp, positions,
velocities and efforts kept, as twinloop's reader keeps them in its table.

    python3 bench/logs/read_python.py FILE.mcap   # prints: messages seconds
"""
import sys
import time

from mcap_ros2.reader import read_ros2_messages


def main(path):
    start = time.perf_counter()
    rows = []
    for m in read_ros2_messages(path, topics=["/joint_states"]):
        msg = m.ros_msg
        st = msg.header.stamp
        rows.append((st.sec * 1_000_000_000 + st.nanosec, list(msg.position),
                     list(msg.velocity), list(msg.effort)))
    print(len(rows), "%.3f" % (time.perf_counter() - start))


if __name__ == "__main__":
    main(sys.argv[1])
