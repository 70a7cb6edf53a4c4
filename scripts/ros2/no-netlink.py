#!/usr/bin/env python3
"""Runs a command that may not open netlink sockets, as under a systemd unit
whose RestrictAddressFamilies= leaves out AF_NETLINK: socket(AF_NETLINK, ...)
fails with EAFNOSUPPORT, through a seccomp filter made with libseccomp (the
shared library systemd itself uses; no headers or Python binding needed).
Exits with 77 where the library or seccomp is not available.

    scripts/ros2/no-netlink.py ubf drive robot.ron
"""
import ctypes
import ctypes.util
import os
import sys

AF_NETLINK = 16
EAFNOSUPPORT = 97
SCMP_ACT_ALLOW = 0x7FFF0000
SCMP_ACT_ERRNO = 0x00050000
SCMP_CMP_EQ = 4


class ArgCmp(ctypes.Structure):
    """libseccomp's struct scmp_arg_cmp."""
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int),
                ("datum_a", ctypes.c_uint64), ("datum_b", ctypes.c_uint64)]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    try:
        lib = ctypes.CDLL(ctypes.util.find_library("seccomp") or "libseccomp.so.2")
    except OSError as e:
        print(f"no libseccomp: {e}", file=sys.stderr)
        sys.exit(77)
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int,
                                           ctypes.c_uint, ctypes.POINTER(ArgCmp)]
    lib.seccomp_load.argtypes = [ctypes.c_void_p]
    filter = lib.seccomp_init(SCMP_ACT_ALLOW)
    family = (ArgCmp * 1)(ArgCmp(0, SCMP_CMP_EQ, AF_NETLINK, 0))
    socket = lib.seccomp_syscall_resolve_name(b"socket")
    if not filter or lib.seccomp_rule_add_array(filter, SCMP_ACT_ERRNO | EAFNOSUPPORT, socket, 1, family) != 0 \
            or lib.seccomp_load(filter) != 0:
        print("seccomp: the filter could not be loaded", file=sys.stderr)
        sys.exit(77)
    os.execvp(sys.argv[1], sys.argv[1:])


main()
