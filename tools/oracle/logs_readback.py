#!/usr/bin/env python3
"""Read an MCAP file twinloop wrote with the reference libraries and print what they
see as JSON: per topic its schema name and encoding, message encoding, message
count, and every decoded value that twinloop's tests compare (f64 bits as hex); and
the file's attachments (name, media type, text) and metadata records (name: pairs).

Decoding goes through `mcap_ros2`'s dynamic decoder, which parses the schema text
the file carries, so a wrong schema or a misaligned CDR field fails here.

    pip install mcap==1.6.0 mcap-ros2-support==0.6.0
    python3 tools/oracle/logs_readback.py FILE.mcap
"""
import json
import struct
import sys

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory


def bits(x):
    return "%016x" % struct.unpack("<Q", struct.pack("<d", float(x)))[0]


def stamp(h):
    return h.stamp.sec * 1_000_000_000 + h.stamp.nanosec


def main(path):
    out = {"topics": {}}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        out["statistics_messages"] = summary.statistics.message_count
        for schema, channel, message, msg in reader.iter_decoded_messages():
            t = out["topics"].setdefault(channel.topic, {
                "schema": schema.name, "schema_encoding": schema.encoding,
                "message_encoding": channel.message_encoding, "metadata": dict(channel.metadata),
                "count": 0, "rows": []})
            t["count"] += 1
            if schema.name == "sensor_msgs/msg/JointState":
                t["names"] = list(msg.name)
                t["rows"].append([stamp(msg.header)] + [bits(x) for x in
                                 list(msg.position) + list(msg.velocity) + list(msg.effort)])
            elif schema.name == "tf2_msgs/msg/TFMessage":
                for tr in msg.transforms:
                    p, q = tr.transform.translation, tr.transform.rotation
                    t["rows"].append([stamp(tr.header), tr.header.frame_id, tr.child_frame_id]
                                     + [bits(x) for x in (p.x, p.y, p.z, q.x, q.y, q.z, q.w)])
            elif schema.name == "sensor_msgs/msg/Imu":
                g, a = msg.angular_velocity, msg.linear_acceleration
                t["rows"].append([stamp(msg.header), msg.header.frame_id]
                                 + [bits(x) for x in (g.x, g.y, g.z, a.x, a.y, a.z)])
            elif schema.name == "std_msgs/msg/Float64MultiArray":
                t["rows"].append([d.label for d in msg.layout.dim] + [bits(x) for x in msg.data])
            elif schema.name == "std_msgs/msg/String":
                t["rows"].append([message.log_time, msg.data])
        out["attachments"] = [{"name": a.name, "media_type": a.media_type,
                               "text": a.data.decode("utf-8")} for a in reader.iter_attachments()]
        out["metadata"] = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main(sys.argv[1])
