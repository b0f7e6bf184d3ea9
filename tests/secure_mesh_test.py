#!/usr/bin/python3
"""scripts/secure_mesh.py: its count of handshake messages and of datagrams by kind in a capture, on
captures made here with known datagrams, and its refusal of bad arguments.

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


def data(writer, sn, little=True, dest=b"D" * 12, request=True, inline_qos=False):
    """A DATA of writer; its payload a ParticipantGenericMessage's start: message_identity (GUID, sequence
    number), related_message_identity (none for a request), destination_participant_key, more."""
    e = "<" if little else ">"
    # extraFlags, octetsToInlineQos, readerId, writerId, writerSN (high, low)
    body = b"\0\0" + struct.pack(e + "H", 16) + b"\0\0\0\0" + writer + struct.pack(e + "iI", 0, sn)
    if inline_qos:  # one parameter, then PID_SENTINEL
        body += struct.pack(e + "HH", 0x70, 4) + b"qqqq" + struct.pack(e + "HH", 1, 0)
    related = bytes(24) if request else b"R" * 24
    body += b"\0\1\0\0" + b"M" * 24 + related + dest + b"\0\0\1\xc1" + b"x" * 40
    return submessage(0x15, body, little) if not inline_qos else \
        bytes([0x15, 3 if little else 2]) + struct.pack(e + "H", len(body)) + body


def rtps(prefix, *subs):
    return b"RTPS\x02\x03\x01\x0f" + prefix + b"".join(subs)


def frame(payload, dport=24910):
    udp = struct.pack(">HHHH", 40000, dport, 8 + len(payload), 0) + payload
    ip = bytes([0x45, 0]) + struct.pack(">H", 20 + len(udp)) + b"\0" * 5 + bytes([17]) + b"\0" * 2 + \
        bytes([127, 0, 0, 1, 127, 0, 0, 1])
    return b"\0" * 12 + b"\x08\x00" + ip + udp  # an Ethernet header, as tcpdump -i lo writes


def pcap(path, frames, times=None, snap=65535):
    """A pcap of frames at times (s), each cut to snap bytes as tcpdump -s does (the record keeps its length)."""
    out = struct.pack("<IHHiIII", 0xA1B2C3D4, 2, 4, 0, 0, snap, 1)
    for f, t in zip(frames, times or [0] * len(frames)):
        out += struct.pack("<IIII", t, 0, min(len(f), snap), len(f)) + f[:snap]
    path.write_bytes(out)


WORK.mkdir(parents=True, exist_ok=True)
a, b, c, d = b"A" * 12, b"B" * 12, b"C" * 12, b"D" * 12
info_ts = submessage(0x09, b"\0" * 8)
announcement = submessage(0x15, b"\0\0\x10\0" + b"\0" * 4 + OTHER + struct.pack("<iI", 0, 7) + b"x" * 8)
frames = [
    frame(rtps(a, info_ts, data(STATELESS, 1, dest=c))),  # A's request to C, sent to one participant ...
    frame(rtps(a, info_ts, data(STATELESS, 1, dest=c)), dport=24912),  # ... and to another
    frame(rtps(b, data(STATELESS, 1, little=False, dest=a, request=False))),  # B's reply to A, big-endian
    # an announcement, then A's final to B, with inline QoS
    frame(rtps(a, announcement, data(STATELESS, 2, dest=b, request=False, inline_qos=True))),
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
if got["handshake_requests"] != 1:
    failures.append("handshake_requests: %r, expected 1 (A 1)" % got["handshake_requests"])
if got["handshake_pairs"] != 2:
    failures.append("handshake_pairs: %r, expected 2 (A and C, A and B)" % got["handshake_pairs"])
rtps_bytes = sum(len(f) - 14 - 20 - 8 for f in frames[:4] if STATELESS in f)
if got["handshake_bytes"] != rtps_bytes:
    failures.append("handshake_bytes: %r, expected %d" % (got["handshake_bytes"], rtps_bytes))

# Cut to 200 bytes (what --pcap keeps) and spread over 25 s: the same counts, the datagrams' full sizes,
# and per 10 s [datagrams, handshake DATA, distinct messages, requests, pairs in a handshake].
long_message = frame(rtps(a, info_ts, data(STATELESS, 3, dest=d) + b"c" * 3000))
cut = WORK / "cut.pcap"
pcap(cut, frames[:4] + [long_message, long_message], times=[100, 101, 109, 110, 125, 125], snap=200)
got_cut = mesh.count_handshakes(str(cut))
want = {"datagrams": 6, "handshake_data": 6, "handshake_messages": 4, "handshake_requests": 2,
        "handshake_pairs": 3, "handshake_bytes": rtps_bytes + 2 * (len(long_message) - 42),
        "handshake_by_10s": [[3, 3, 2, 1, 2], [1, 1, 1, 0, 1], [2, 2, 1, 1, 1]],
        "kinds": {"handshake": 6}, "kinds_by_10s": [{"handshake": 3}, {"handshake": 1}, {"handshake": 2}]}
if got_cut != want:
    failures.append("a capture cut to 200 bytes: %r, expected %r" % (got_cut, want))
# Cut before the destinations: the messages are still counted, their pairs are not.
short = WORK / "short.pcap"
pcap(short, frames[:4], snap=110)
got_short = mesh.count_handshakes(str(short))
if (got_short["handshake_messages"], got_short["handshake_pairs"], got_short["handshake_requests"]) != (3, 0, 0):
    failures.append("a capture cut to 110 bytes: %r, expected 3 messages, no pair, no request" % got_short)
# Datagrams by kind: one of each, a handshake and an announcement in one datagram counting as the handshake.
def acknack(base_high, base_low, bits):
    return submessage(0x06, b"\0\0\0\0" + OTHER + struct.pack("<iII", base_high, base_low, bits) + struct.pack("<i", 1))


def protected(key_id):  # SEC_PREFIX (transformation kind, key id, session, IV), SEC_BODY, SEC_POSTFIX
    return submessage(0x31, b"\0\0\2\1" + key_id + b"s" * 8) + submessage(0x30, b"x" * 24) + \
        submessage(0x32, b"m" * 20)


kind_frames = [frames[3], frame(rtps(a, info_ts, announcement)), frame(rtps(b, protected(bytes(4)))),
               frame(rtps(b, protected(b"\0\0\0\7"))), frame(rtps(c, info_ts, data(OTHER[::-1], 5))),
               frame(rtps(c, acknack(0, 0, 0))), frame(rtps(c, acknack(0, 0, 0)), dport=24912),
               frame(rtps(d, acknack(0, 1, 0))), frame(rtps(d, submessage(0x07, b"\0" * 28))),
               frame(rtps(d, info_ts))]
kinds = WORK / "kinds.pcap"
pcap(kinds, kind_frames, times=[0, 0, 0, 0, 0, 12, 12, 12, 12, 12], snap=200)
got_kinds = mesh.count_handshakes(str(kinds))
want_kinds = {"handshake": 1, "announcement": 1, "key_exchange": 1, "protected": 1, "data": 1, "initial_acknack": 2,
              "acknack": 1, "heartbeat": 1, "other": 1}
if got_kinds["kinds"] != want_kinds or list(got_kinds["kinds"]) != list(mesh.KINDS):
    failures.append("datagrams by kind: %r, expected %r" % (got_kinds["kinds"], want_kinds))
want_by_10s = [{"handshake": 1, "announcement": 1, "key_exchange": 1, "protected": 1, "data": 1},
               {"initial_acknack": 2, "acknack": 1, "heartbeat": 1, "other": 1}]
if got_kinds["kinds_by_10s"] != want_by_10s:
    failures.append("datagrams by kind per 10 s: %r, expected %r" % (got_kinds["kinds_by_10s"], want_by_10s))

stats = mesh.capture_stats("tcpdump: listening on lo\n1230038 packets captured\n8058180 packets received by filter\n"
                           "5545522 packets dropped by kernel\n")
if stats != {"capture_kept": 1230038, "capture_seen": 8058180, "capture_dropped": 5545522}:
    failures.append("tcpdump's counts: %r" % stats)

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
