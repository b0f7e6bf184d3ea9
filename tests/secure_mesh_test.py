#!/usr/bin/python3
"""scripts/secure_mesh.py: its count of handshake messages in a capture, on a capture made here with
known datagrams, and its refusal of bad arguments.

  tests/secure_mesh_test.py SOURCE_DIR WORK_DIR
"""
import importlib.util
import struct
import subprocess
import sys
from pathlib import Path

SOURCE, WORK = Path(sys.argv[1]), Path(sys.argv[2])
spec = importlib.util.spec_from_file_location("secure_mesh", SOURCE / "scripts" / "secure_mesh.py")
mesh = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mesh)

STATELESS = bytes.fromhex("000201c3")
OTHER = bytes.fromhex("000100c2")  # the participant announcer


def submessage(sid, body, little=True):
    return bytes([sid, 1 if little else 0]) + struct.pack("<H" if little else ">H", len(body)) + body


def data(writer, sn, little=True):
    # extraFlags, octetsToInlineQos, readerId, writerId, writerSN (high, low), then a payload
    body = b"\0\0\x10\0" + b"\0\0\0\0" + writer + struct.pack("<iI" if little else ">iI", 0, sn) + b"x" * 40
    return submessage(0x15, body, little)


def rtps(prefix, *subs):
    return b"RTPS\x02\x03\x01\x0f" + prefix + b"".join(subs)


def frame(payload, dport=24910):
    udp = struct.pack(">HHHH", 40000, dport, 8 + len(payload), 0) + payload
    ip = bytes([0x45, 0]) + struct.pack(">H", 20 + len(udp)) + b"\0" * 5 + bytes([17]) + b"\0" * 2 + \
        bytes([127, 0, 0, 1, 127, 0, 0, 1])
    return b"\0" * 12 + b"\x08\x00" + ip + udp  # an Ethernet header, as tcpdump -i lo writes


def pcap(path, frames):
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, 65535, 1)
    for f in frames:
        out += struct.pack("<IIII", 0, 0, len(f), len(f)) + f
    path.write_bytes(out)


WORK.mkdir(parents=True, exist_ok=True)
a, b = b"A" * 12, b"B" * 12
info_ts = submessage(0x09, b"\0" * 8)
frames = [
    frame(rtps(a, info_ts, data(STATELESS, 1))),  # A's message 1 to one peer ...
    frame(rtps(a, info_ts, data(STATELESS, 1)), dport=24912),  # ... and to another
    frame(rtps(b, data(STATELESS, 1, little=False))),  # B's message 1, big-endian
    frame(rtps(a, data(OTHER, 7), data(STATELESS, 2))),  # an announcement, then A's message 2
    frame(b"not rtps at all"),
]
cap = WORK / "handshakes.pcap"
pcap(cap, frames)
got = mesh.count_handshakes(str(cap))
failures = []
if got["datagrams"] != 4:
    failures.append("datagrams: %r, expected 4 RTPS datagrams" % got["datagrams"])
if got["handshake_data"] != 4:
    failures.append("handshake_data: %r, expected 4 DATA of writer 0x000201c3" % got["handshake_data"])
if got["handshake_messages"] != 3:
    failures.append("handshake_messages: %r, expected 3 (A 1, A 2, B 1)" % got["handshake_messages"])

script = SOURCE / "scripts" / "secure_mesh.py"
for args, needle in ((["-n", "1"], "-n must be at least 2"), (["-n", "10", "--groups", "3"], "must divide"),
                     (["-n", "4", "--set", "lease"], "is not key=value"),
                     (["-n", "4", "--gate", "-1"], "--gate -1 must be at least 0")):
    r = subprocess.run([sys.executable, str(script)] + args, capture_output=True, text=True, timeout=60)
    if r.returncode != 2 or needle not in r.stderr:
        failures.append("%s: exit %d, stderr %r (expected 2 and %r)" % (" ".join(args), r.returncode,
                                                                       r.stderr.strip(), needle))
if failures:
    print("\n".join(failures))
    sys.exit(1)
print("ok: %r" % got)
