#!/usr/bin/env python3
"""Byte-preserving ARCOS proxy between `ubf drive` and AMRISim that logs truth.

Every client packet is forwarded unchanged (whole packets, in order). Once the
first SIP comes back from AMRISim, the proxy injects SIM_STAT 2 (command 237:
a SIMSTAT packet, type 0x62, before every SIP). SIMSTAT packets are parsed,
logged and NOT forwarded, so ubf sees exactly AMRISim's other packets.
Raw SIP odometry (x, y mm; th in 2pi/4096 units) is logged too.

Optional synthetic heading drift (--nudge-at-m, --nudge-deg): when the true
distance travelled from the start passes each listed value, the proxy sends
SIM_SET_POSE (command 224) with the current true x, y and the true heading
(whole degrees, AMRISim's resolution) plus --nudge-deg: the robot turns in
the simulator while its odometry does not (AMRISim's documented semantics).

usage: truth-proxy.py LISTEN_PORT UPSTREAM_PORT TRUTH_CSV [--nudge-at-m 5,10,15 --nudge-deg 1]
"""
import math
import select
import socket
import struct
import sys
import time


def checksum(body: bytes) -> int:
    s = 0
    n = len(body) - len(body) % 2
    for i in range(0, n, 2):
        s = (s + ((body[i] << 8) | body[i + 1])) & 0xFFFF
    if len(body) % 2:
        s ^= body[-1]
    return s


def frame(body: bytes) -> bytes:
    return b"\xfa\xfb" + bytes([len(body) + 2]) + body + struct.pack(">H", checksum(body))


def split_packets(buf: bytearray):
    """Whole packets off the front of buf (resynchronising on the header)."""
    out = []
    while True:
        i = buf.find(b"\xfa\xfb")
        if i < 0:
            # keep a possible trailing 0xfa
            if buf and buf[-1] == 0xFA:
                junk = bytes(buf[:-1]); del buf[:-1]
            else:
                junk = bytes(buf); buf.clear()
            if junk:
                out.append(("junk", junk))
            return out
        if i > 0:
            out.append(("junk", bytes(buf[:i])))
            del buf[:i]
        if len(buf) < 3:
            return out
        total = 3 + buf[2]
        if len(buf) < total:
            return out
        out.append(("pkt", bytes(buf[:total])))
        del buf[:total]


def main():
    listen_port, up_port, truth_path = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
    nudge_at, nudge_deg = [], 0
    args = sys.argv[4:]
    while args:
        if args[0] == "--nudge-at-m":
            nudge_at = [float(v) for v in args[1].split(",")]
        elif args[0] == "--nudge-deg":
            # Whole degrees: SIM_SET_POSE and SIMSTAT carry no finer heading.
            nudge_deg = int(args[1])
        else:
            sys.exit(f"truth-proxy.py: unknown option {args[0]} (see the usage above)")
        args = args[2:]

    ls = socket.socket()
    ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    ls.bind(("127.0.0.1", listen_port))
    ls.listen(1)
    print(f"proxy listening on {listen_port}", flush=True)
    cli, _ = ls.accept()
    up = socket.create_connection(("127.0.0.1", up_port))
    for s in (cli, up):
        s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    log = open(truth_path, "w")
    log.write("t,kind,a,b,c,d\n")
    t0 = time.monotonic()
    cbuf, sbuf = bytearray(), bytearray()
    simstat_on = False
    start = None
    nudges_done = 0
    n_simstat = 0
    while True:
        r, _, _ = select.select([cli, up], [], [], 5.0)
        if not r:
            continue
        if cli in r:
            data = cli.recv(65536)
            if not data:
                break
            cbuf += data
            for kind, p in split_packets(cbuf):
                up.sendall(p)
                if kind == "pkt" and len(p) >= 4:
                    log.write(f"{time.monotonic()-t0:.3f},cmd,{p[3]},{p[4] if len(p)>6 else ''},,\n")
        if up in r:
            data = up.recv(65536)
            if not data:
                break
            sbuf += data
            for kind, p in split_packets(sbuf):
                if kind == "pkt" and p[3] == 0x62:
                    b = p[3:-2]
                    # type, 2 empty strings, flags u4, 3 x u2, x y z th i4
                    flags, = struct.unpack_from("<I", b, 3)
                    x, y, z, th = struct.unpack_from("<iiii", b, 13)
                    now = time.monotonic() - t0
                    log.write(f"{now:.3f},true,{x},{y},{th},{flags}\n")
                    n_simstat += 1
                    if start is None:
                        start = (x, y)
                    d = math.hypot(x - start[0], y - start[1]) / 1000.0
                    if nudges_done < len(nudge_at) and d >= nudge_at[nudges_done]:
                        nth = th + nudge_deg
                        body = bytes([224, 0x3B]) + struct.pack("<iii", x, y, nth)
                        up.sendall(frame(body))
                        log.write(f"{now:.3f},nudge,{x},{y},{nth},{d:.3f}\n")
                        nudges_done += 1
                    continue  # strip SIMSTAT
                cli.sendall(p)
                if kind == "pkt" and (p[3] & 0xF0) == 0x30 and len(p) > 12:
                    x, y, th = struct.unpack_from("<HHh", p, 4)
                    log.write(f"{time.monotonic()-t0:.3f},sip,{x & 0x7FFF},{y & 0x7FFF},{th},{p[3]}\n")
                    if not simstat_on:
                        up.sendall(frame(bytes([237, 0x3B, 2, 0])))
                        simstat_on = True
        log.flush()
    log.close()
    print(f"proxy done: {n_simstat} SIMSTAT packets", flush=True)


if __name__ == "__main__":
    main()
