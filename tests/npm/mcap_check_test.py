#!/usr/bin/env python3
"""shapeform's MCAP files read by readers others wrote (@mcap/core, @foxglove/*), message for message
against shapeform's own reader.

Usage: mcap_check_test.py FIXTURE_PROGRAM SHAPEFORM_MCAP_PROGRAM NPM_NODE_MODULES WORK_DIR

FIXTURE_PROGRAM (shapeform_mcap_fixture) writes complete files (none, zstd, lz4) and a killed one, with
what McapReader reads back from each (X.expected.jsonl). For each file, tests/npm/mcap_check.mjs --decode
must print the same messages (topic, log time, decoded CDR or JSON) in the same order; the killed file is
read by McapStreamReader. Then `shapeform_mcap recover` rewrites the killed file and the indexed reader
reads the same messages from the result. Fails (never skips) when the npm validators are missing.
"""
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd, env=None):
    p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    if p.returncode != 0:
        sys.exit("FAIL: %s exited %d\nstderr: %s" % (" ".join(cmd), p.returncode, p.stderr[-4000:]))
    return p.stdout


def main(fixture, tool, npm, work):
    if not os.path.isdir(os.path.join(npm, "@mcap", "core")):
        sys.exit("FAIL: the npm validators are missing from %s: run scripts/install_deps.sh" % npm)
    node = shutil.which("node")
    if not node:
        sys.exit("FAIL: node is not installed: run scripts/install_deps.sh")
    shutil.rmtree(work, ignore_errors=True)
    run([fixture, work])
    env = dict(os.environ, SHAPEFORM_NPM=npm)
    check = os.path.join(HERE, "mcap_check.mjs")
    files = ["complete_none", "complete_zstd", "complete_lz4", "killed"]
    for name in files:
        path = os.path.join(work, name + ".mcap")
        with open(os.path.join(work, name + ".expected.jsonl")) as f:
            expected = [json.loads(line) for line in f if line.strip()]
        got = [json.loads(line) for line in run([node, check, path, "--decode"], env).splitlines() if line.strip()]
        summary = json.loads(run([node, check, path], env))
        want_mode = "stream" if name == "killed" else "indexed"
        if summary["mode"] != want_mode:
            sys.exit("FAIL: %s read in mode %s, expected %s" % (name, summary["mode"], want_mode))
        if name == "killed" and summary["truncated_bytes"] == 0:
            sys.exit("FAIL: killed.mcap: the stream reader saw no record cut short")
        if len(expected) < 10:
            sys.exit("FAIL: %s: only %d messages expected: the fixture is wrong" % (name, len(expected)))
        if len(got) != len(expected):
            sys.exit("FAIL: %s: @mcap/core read %d messages, shapeform's reader %d" % (name, len(got), len(expected)))
        for i, (g, e) in enumerate(zip(got, expected)):
            if g != e:
                sys.exit("FAIL: %s: message %d differs:\n  @mcap/core: %s\n  shapeform:  %s" % (name, i, g, e))
        print("%s: %d messages agree (%s)" % (name, len(got), summary["mode"]))
    # The killed file made durable: complete, indexed, the same messages.
    killed = os.path.join(work, "killed.mcap")
    fixed = os.path.join(work, "recovered.mcap")
    run([tool, "recover", killed, fixed])
    with open(os.path.join(work, "killed.expected.jsonl")) as f:
        expected = [json.loads(line) for line in f if line.strip()]
    got = [json.loads(line) for line in run([node, check, fixed, "--decode"], env).splitlines() if line.strip()]
    if json.loads(run([node, check, fixed], env))["mode"] != "indexed":
        sys.exit("FAIL: recovered.mcap is not a complete file")
    if got != expected:
        sys.exit("FAIL: recovered.mcap: %d messages, expected %d, or they differ" % (len(got), len(expected)))
    print("recovered: %d messages agree (indexed)" % len(got))
    info = json.loads(run([tool, "info", fixed, "--json"]))
    if not info["complete"] or info["messages"] != len(expected):
        sys.exit("FAIL: shapeform_mcap info on recovered.mcap: %s" % info)
    # Bad input: exit 2 with the reason.
    for args, words in (([tool, "info", os.path.join(work, "missing.mcap")], "does not exist"),
                        ([tool, "info", os.path.join(work, "killed.expected.jsonl")], "not an MCAP file"),
                        ([tool, "info", fixed, "--bogus"], "--bogus"),
                        ([tool, "recover", killed, killed], "is IN")):
        p = subprocess.run(args, capture_output=True, text=True, timeout=60)
        if p.returncode != 2 or words not in p.stderr:
            sys.exit("FAIL: %s: exit %d, stderr %r (expected 2 and %r)" % (" ".join(args), p.returncode, p.stderr, words))
    helped = run([tool, "--help"])
    if "recover IN OUT" not in helped or "info FILE" not in helped:
        sys.exit("FAIL: shapeform_mcap --help does not describe info and recover:\n" + helped)
    print("PASS")


if __name__ == "__main__":
    if len(sys.argv) != 5:
        sys.exit(__doc__)
    main(*sys.argv[1:])
