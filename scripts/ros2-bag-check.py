#!/usr/bin/env python3
"""Reads a rosbag2-style MCAP log with two ROS 2 readers we did not write.

    python3 scripts/ros2-bag-check.py out/run/run-rosbag2/run-rosbag2_0.mcap [--expect-topic /odom ...]

Installs mcap-ros2-support 0.6.0 and rosbags 0.11.9 into .venv-rosbag on first
use (scripts/script_env.py), then:

1. checks the MCAP header's profile is `ros2`, every channel's message
   encoding `cdr` and every schema's encoding `ros2msg`;
2. decodes every message with mcap_ros2.reader.read_ros2_messages;
3. decodes every message with rosbags' AnyReader, which reads the rosbag2
   directory: the .mcap's folder must hold the metadata.yaml our writer writes
   (every schema text is also parsed with rosbags.typesys.get_types_from_msg,
   so ubf_msgs and any other type decode from the file alone);
4. prints one JSON object: per topic, its type, the messages in the file, the
   counts each reader decoded, the count metadata.yaml gives, and the first
   message's fields summarised.

It exits non-zero, naming the first message that failed to decode, if any
check fails: a count that differs between the file, a reader and
metadata.yaml, a first message the two readers decode differently, or an
--expect-topic that holds no message.
"""
import argparse
import array
import dataclasses
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import script_env  # noqa: E402  (scripts/script_env.py)

PACKAGES = ["mcap-ros2-support==0.6.0", "rosbags==0.11.9"]


def plain(value):
    """A decoded message (either reader's) as JSON-ready lists, dicts and scalars."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):  # rosbags
        return {f.name: plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not f.name.startswith("__")}  # not __msgtype__
    if isinstance(getattr(type(value), "__slots__", None), list):  # mcap_ros2's classes
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if hasattr(value, "tolist"):  # numpy arrays and scalars (rosbags)
        return plain(value.tolist())
    if isinstance(value, (bytes, bytearray, memoryview)):
        return list(bytes(value))
    if isinstance(value, (list, tuple, array.array)):
        return [plain(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return value


def summary(value):
    """plain(), with long arrays and strings cut short."""
    if isinstance(value, dict):
        return {k: summary(v) for k, v in value.items()}
    if isinstance(value, list):
        if len(value) > 6:
            return {"len": len(value), "first": [summary(v) for v in value[:3]]}
        return [summary(v) for v in value]
    if isinstance(value, str) and len(value) > 80:
        return value[:77] + "..."
    return value


def scan(path):
    """Header, schemas, channels and per-channel message counts, from every record."""
    from mcap.records import Channel, Header, Message, Schema
    from mcap.stream_reader import StreamReader

    header, schemas, channels, counts = None, {}, {}, {}
    with open(path, "rb") as f:
        for record in StreamReader(f, skip_magic=False).records:
            if isinstance(record, Header):
                header = record
            elif isinstance(record, Schema):
                schemas[record.id] = record
            elif isinstance(record, Channel):
                channels[record.id] = record
            elif isinstance(record, Message):
                counts[record.channel_id] = counts.get(record.channel_id, 0) + 1
    return header, schemas, channels, counts


def check_encodings(header, schemas, channels, errors):
    if header is None or header.profile != "ros2":
        errors.append(f"header profile is {header.profile if header else None!r}, not 'ros2'")
    for channel in channels.values():
        if channel.message_encoding != "cdr":
            errors.append(f"{channel.topic}: message encoding {channel.message_encoding!r}, not 'cdr'")
        if channel.schema_id not in schemas:
            errors.append(f"{channel.topic}: no schema (schema id {channel.schema_id})")
    for schema in schemas.values():
        if schema.encoding != "ros2msg":
            errors.append(f"schema {schema.name}: encoding {schema.encoding!r}, not 'ros2msg'")


def check_definitions(schemas, errors):
    """Each type, top or nested, must be defined alike in every schema: rosbags keeps one
    definition per type name for the whole bag, so a conflicting one breaks other topics."""
    seen = {}
    for schema in schemas.values():
        name = schema.name
        for i, section in enumerate(schema.data.decode().split("=" * 80 + "\n")):
            lines = section.split("\n")
            if i > 0 and lines[0].startswith("MSG: "):
                name, lines = lines[0][5:].strip(), lines[1:]
            package, _, short = name.partition("/")
            key = f"{package}/msg/{short.split('/')[-1]}"
            fields = [" ".join(line.split("#")[0].split()) for line in lines]
            fields = [f for f in fields if f]
            if key in seen and seen[key][1] != fields:
                errors.append(f"type {key} is defined differently in schemas {seen[key][0]} and {schema.name}")
            seen.setdefault(key, (schema.name, fields))


def read_mcap_ros2(path, errors):
    """Decode every message with read_ros2_messages; on a failure, find the message."""
    from mcap_ros2.reader import read_ros2_messages

    counts, first = {}, {}
    try:
        for msg in read_ros2_messages(path):
            topic = msg.channel.topic
            counts[topic] = counts.get(topic, 0) + 1
            first.setdefault(topic, plain(msg.ros_msg))
    except Exception as err:  # noqa: BLE001 (any failure is the reader's verdict)
        errors.append(f"mcap_ros2: {first_failure(path) or 'a message'} failed to decode: "
                      f"{type(err).__name__}: {err}")
    return counts, first


def first_failure(path):
    """The first message (log-time order, as read_ros2_messages goes) mcap_ros2 can't decode."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    factory, seen = DecoderFactory(), {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=True):
            seen[channel.topic] = seen.get(channel.topic, 0) + 1
            try:
                decoder = factory.decoder_for(channel.message_encoding, schema)
                if decoder is None:
                    raise ValueError("no decoder for this encoding")
                decoder(message.data)
            except Exception as err:  # noqa: BLE001
                return (f"message {seen[channel.topic]} on {channel.topic} "
                        f"(schema {schema.name if schema else None}, log time {message.log_time})")
    return None


def read_metadata(directory, mcap_name, errors):
    """metadata.yaml as rosbag2 wrote it, or None (with the reason in errors)."""
    from ruamel.yaml import YAML

    path = os.path.join(directory, "metadata.yaml")
    if not os.path.exists(path):
        errors.append(f"no metadata.yaml beside the .mcap in {directory}: rosbags (and ros2 bag) "
                      f"read a rosbag2 directory, and our writer is meant to write one")
        return None
    with open(path) as f:
        info = YAML(typ="safe").load(f).get("rosbag2_bagfile_information")
    if not info:
        errors.append("metadata.yaml has no rosbag2_bagfile_information")
        return None
    names = [os.path.basename(p) for p in info.get("relative_file_paths", [])]
    if mcap_name not in names:
        errors.append(f"metadata.yaml's relative_file_paths {names} do not list {mcap_name}")
    return info


def read_rosbags(directory, schemas, errors):
    """Decode every message of the rosbag2 directory with rosbags' AnyReader."""
    from pathlib import Path

    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore, get_types_from_msg

    types = {}
    for schema in schemas.values():
        try:
            types.update(get_types_from_msg(schema.data.decode(), schema.name))
        except Exception as err:  # noqa: BLE001
            errors.append(f"rosbags: schema {schema.name} does not parse: {type(err).__name__}: {err}")
    store = get_typestore(Stores.EMPTY)
    store.register(types)

    counts, first = {}, {}
    try:
        # AnyReader registers the types of every schema in the bag itself; the store built above
        # is what it falls back on for a bag without schemas.
        with AnyReader([Path(directory)], default_typestore=store) as reader:
            for connection, timestamp, raw in reader.messages(connections=reader.connections):
                topic = connection.topic
                try:
                    message = reader.deserialize(raw, connection.msgtype)
                except Exception as err:  # noqa: BLE001
                    errors.append(f"rosbags: message {counts.get(topic, 0) + 1} on {topic} "
                                  f"({connection.msgtype}, time {timestamp}) failed to decode: "
                                  f"{type(err).__name__}: {err}")
                    break
                counts[topic] = counts.get(topic, 0) + 1
                first.setdefault(topic, plain(message))
    except Exception as err:  # noqa: BLE001
        errors.append(f"rosbags: could not open {directory}: {type(err).__name__}: {err}")
    return counts, first


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("mcap", help="the .mcap inside a rosbag2 directory")
    parser.add_argument("--expect-topic", action="append", default=[], metavar="TOPIC",
                        help="a topic that must hold at least one message (repeatable)")
    args = parser.parse_args()
    script_env.ensure(".venv-rosbag", PACKAGES, ["mcap_ros2", "rosbags"])
    from importlib.metadata import version

    path = os.path.abspath(args.mcap)
    directory = os.path.dirname(path)
    errors = []

    header, schemas, channels, in_file = scan(path)
    check_encodings(header, schemas, channels, errors)
    check_definitions(schemas, errors)
    types = {c.topic: schemas[c.schema_id].name if c.schema_id in schemas else None
             for c in channels.values()}
    file_counts = {}
    for channel_id, count in in_file.items():
        topic = channels[channel_id].topic
        file_counts[topic] = file_counts.get(topic, 0) + count

    m_counts, m_first = read_mcap_ros2(path, errors)
    info = read_metadata(directory, os.path.basename(path), errors)
    r_counts, r_first, yaml_counts = {}, {}, {}
    if info is not None:
        r_counts, r_first = read_rosbags(directory, schemas, errors)
        for entry in info.get("topics_with_message_count", []):
            meta = entry.get("topic_metadata", {})
            yaml_counts[meta.get("name")] = entry.get("message_count")
            if meta.get("name") in types and meta.get("type") != types[meta.get("name")]:
                errors.append(f"{meta.get('name')}: metadata.yaml says type {meta.get('type')}, "
                              f"the file's schema is {types[meta.get('name')]}")
        total = info.get("message_count")
        if total != sum(file_counts.values()):
            errors.append(f"metadata.yaml message_count {total}, the file holds {sum(file_counts.values())}")

    report = {"file": args.mcap, "profile": header.profile if header else None,
              "library": header.library if header else None,
              "readers": {"mcap-ros2-support": version("mcap-ros2-support"),
                          "rosbags": version("rosbags")},
              "topics": {}}
    for topic in sorted(types):
        n = file_counts.get(topic, 0)
        entry = {"type": types[topic], "messages": n,
                 "mcap_ros2": m_counts.get(topic, 0), "rosbags": r_counts.get(topic, 0),
                 "metadata_yaml": yaml_counts.get(topic)}
        channel = next(c for c in channels.values() if c.topic == topic)
        if "offered_qos_profiles" not in channel.metadata:
            entry["note"] = "channel metadata has no offered_qos_profiles (the ros2 profile asks for it)"
        first = m_first.get(topic, r_first.get(topic))
        if first is not None:
            entry["first"] = summary(first)
        report["topics"][topic] = entry
        if not any(e.startswith(("mcap_ros2:", "rosbags:")) for e in errors):
            if entry["mcap_ros2"] != n:
                errors.append(f"{topic}: mcap_ros2 decoded {entry['mcap_ros2']} of {n} messages")
            if info is not None and entry["rosbags"] != n:
                errors.append(f"{topic}: rosbags decoded {entry['rosbags']} of {n} messages (rosbags "
                              f"drops a topic whose metadata.yaml entry (type, serialization_format, "
                              f"offered_qos_profiles) differs from the MCAP channel's)")
        if info is not None and entry["metadata_yaml"] != n:
            errors.append(f"{topic}: metadata.yaml says {entry['metadata_yaml']} messages, the file holds {n}")
        if topic in m_first and topic in r_first and m_first[topic] != r_first[topic]:
            errors.append(f"{topic}: the two readers decode the first message differently")
    for topic in args.expect_topic:
        if not file_counts.get(topic):
            errors.append(f"expected topic {topic} holds no message")
    report["ok"] = not errors
    if errors:
        report["errors"] = errors
    print(json.dumps(report, indent=2))
    if errors:
        failed = [e for e in errors if e.startswith(("mcap_ros2: message", "rosbags: message"))]
        more = f" ({len(errors)} problems: see errors above)" if len(errors) > 1 else ""
        sys.exit(f"ros2-bag-check: {(failed or errors)[0]}{more}")


if __name__ == "__main__":
    main()
