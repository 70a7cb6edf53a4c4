#!/usr/bin/env python3
"""Reads a run log (run.mcap) with the MCAP project's own Python reader.

    python3 scripts/mcap-check.py out/run/run.mcap
    python3 scripts/mcap-check.py --cut-short drive-log.mcap   # a killed process's log

Installs the `mcap` and `jsonschema` packages from PyPI into .venv-mcap on
first use (scripts/script_env.py), then prints each topic with its schema,
encoding and message count, the first and last true pose, the camera images
if the log holds them, and the report's end. It exits non-zero if a
message's JSON does not parse or does not validate against its channel's
JSON Schema, if a schema describes no fields, if an image is not a PNG, or
if a topic the log must hold is missing: a check of our writer by a reader
and a validator we did not write. A drive's log (its /run names a drive)
has no true pose and must carry its start's UTC time (metadata
`ubf.wall_clock`); with --cut-short, the log of a process that was killed
need not have its /report.
"""
import base64
import json
import struct
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import script_env  # noqa: E402  (scripts/script_env.py)

REQUIRED = ["/pose/true", "/pose/odometry", "/tree", "/world", "/run", "/scene", "/report"]
REQUIRED_DRIVE = ["/pose/odometry", "/tree", "/run", "/report"]


def main():
    script_env.ensure(".venv-mcap", ["mcap", "jsonschema"], ["mcap", "jsonschema"])
    import jsonschema
    from mcap.reader import make_reader

    args = sys.argv[1:]
    cut_short = "--cut-short" in args
    args = [a for a in args if a != "--cut-short"]
    if len(args) != 1:
        sys.exit(__doc__)
    counts, schemas, first, last, report, images, drive = {}, {}, None, None, None, {}, False
    with open(args[0], "rb") as f:
        validators = {}
        for schema, channel, message in make_reader(f).iter_messages():
            data = json.loads(message.data)
            if schema.id not in validators:
                described = json.loads(schema.data)
                if not described.get("properties"):
                    sys.exit(f"{channel.topic}: schema {schema.name} describes no fields")
                validators[schema.id] = jsonschema.Draft202012Validator(described)
            errors = list(validators[schema.id].iter_errors(data))
            if errors:
                sys.exit(f"{channel.topic}: message {counts.get(channel.topic, 0) + 1} does not fit {schema.name}: "
                         f"{errors[0].message}")
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            schemas[channel.topic] = (schema.name if schema else "", schema.encoding if schema else "",
                                      channel.message_encoding)
            if channel.topic == "/run":
                drive = data["scenario"].startswith("drive")
            if channel.topic == ("/pose/odometry" if drive else "/pose/true"):
                position = data["pose"]["position"]
                first = first or (position["x"], position["y"])
                last = (position["x"], position["y"])
            if channel.topic == "/report":
                report = data
            if channel.topic.startswith("/camera/"):
                png = base64.b64decode(data["data"], validate=True)
                # The signature, then the IHDR chunk: width and height.
                if png[:8] != b"\x89PNG\r\n\x1a\n" or png[12:16] != b"IHDR" or data["format"] != "png":
                    sys.exit(f"{channel.topic}: message {counts[channel.topic]} is not a PNG")
                images[channel.topic] = struct.unpack(">II", png[16:24])
    print("| topic | schema | schema encoding | message encoding | messages |")
    print("| --- | --- | --- | --- | --- |")
    for topic in sorted(counts):
        name, encoding, message_encoding = schemas[topic]
        print(f"| {topic} | {name} | {encoding} | {message_encoding} | {counts[topic]} |")
    if drive:
        with open(args[0], "rb") as f:
            clock = {m.name: m.metadata for m in make_reader(f).iter_metadata()}.get("ubf.wall_clock")
        if not clock:
            sys.exit("a drive's log must say when it started: no ubf.wall_clock metadata")
        print(f"started at {clock['utc_start']} (UTC)")
    required = REQUIRED_DRIVE if drive else REQUIRED
    missing = [t for t in required if t not in counts and not (cut_short and t == "/report")]
    if missing:
        sys.exit(f"missing topics: {', '.join(missing)}")
    for topic, (width, height) in sorted(images.items()):
        print(f"{topic}: {counts[topic]} PNG images of {width} x {height}")
    ended = report["end"] if report else "not recorded (cut short)"
    print(f"{'odometric' if drive else 'true'} pose from ({first[0]:.2f}, {first[1]:.2f}) to "
          f"({last[0]:.2f}, {last[1]:.2f}); the run ended: {ended}")


if __name__ == "__main__":
    main()
