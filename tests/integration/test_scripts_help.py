#!/usr/bin/env python3
"""Every script answers --help with its usage and does nothing else.

The scripts: every file of scripts/ (each must be executable), every file with a #! line in a folder of
scripts/ (scripts/paper/run.py, ...; the others there are modules), bench/bench.py,
bench/bench_report.py and bench/sim_loop_count.py. Each is run as `SCRIPT --help`; it must exit 0, print a usage line naming
itself on stdout, and change nothing in the source tree (no build started, no file written).

    python3 tests/integration/test_scripts_help.py --source . [unittest args]
"""
import argparse
import os
import subprocess
import sys
import unittest

SOURCE = None


def scripts():
    """Paths (relative to the source folder) of the scripts."""
    found = []
    top = os.path.join(SOURCE, "scripts")
    for root, dirs, files in os.walk(top):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        for f in sorted(files):
            path = os.path.join(root, f)
            with open(path, "rb") as fh:
                shebang = fh.read(2) == b"#!"
            if root == top or shebang:
                found.append(os.path.relpath(path, SOURCE))
    return found + ["bench/bench.py", "bench/bench_report.py", "bench/sim_loop_count.py"]


def tree_state():
    """(path, size, mtime) of every file of the source tree outside build folders and .git."""
    state = set()
    for root, dirs, files in os.walk(SOURCE):
        if root == SOURCE:
            dirs[:] = [d for d in dirs if not d.startswith("build") and d != ".git"]
        for f in files:
            path = os.path.join(root, f)
            try:
                st = os.stat(path)
            except FileNotFoundError:
                continue
            state.add((os.path.relpath(path, SOURCE), st.st_size, st.st_mtime_ns))
    return state


class ScriptsHelp(unittest.TestCase):

    def test_every_script_answers_help_and_does_nothing_else(self):
        listed = scripts()
        self.assertIn("scripts/launch_swarm.sh", listed)
        self.assertIn("scripts/paper/run.py", listed)
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        for rel in listed:
            with self.subTest(script=rel):
                path = os.path.join(SOURCE, rel)
                self.assertTrue(os.access(path, os.X_OK), "%s is not executable" % rel)
                before = tree_state()
                r = subprocess.run([path, "--help"], capture_output=True, text=True, timeout=60, cwd=SOURCE,
                                   stdin=subprocess.DEVNULL, env=env)
                self.assertEqual(r.returncode, 0, "%s --help: exit %d, stderr %r" % (rel, r.returncode, r.stderr[-500:]))
                name = os.path.basename(rel)
                self.assertTrue(any(name in line for line in r.stdout.splitlines()),
                                "%s --help: no usage line naming %s on stdout: %r" % (rel, name, r.stdout[:500]))
                changed = sorted({p for p, _, _ in before ^ tree_state()})
                self.assertEqual(changed, [], "%s --help changed the tree" % rel)

    def test_reliability_refuses_bad_arguments_before_starting_anything(self):
        # Each is checked before root, the build or a test host: exit 2, a message naming the option.
        script = os.path.join(SOURCE, "scripts", "reliability.sh")
        env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
        for args, named in ((["--quick", "--runs", "0", "--only", "kill"], "--runs"),
                            (["--runs", "x"], "--runs"),
                            (["--only", "kill,nosuch"], "nosuch"),
                            (["--laws", "paper,spiral"], "spiral"),
                            (["--losses", "0,120"], "--losses"),
                            (["--frobnicate"], "--frobnicate")):
            with self.subTest(args=args):
                before = tree_state()
                r = subprocess.run([script] + args, capture_output=True, text=True, timeout=60, cwd=SOURCE,
                                   stdin=subprocess.DEVNULL, env=env)
                self.assertEqual(r.returncode, 2, "reliability.sh %s: exit %d, stderr %r" % (args, r.returncode,
                                                                                              r.stderr[-500:]))
                self.assertIn(named, r.stderr)
                self.assertEqual(sorted({p for p, _, _ in before ^ tree_state()}), [], "the tree changed")
        # A valid plan only prints itself with --dry-run.
        r = subprocess.run([script, "--quick", "--runs", "1", "--only", "kill", "--dry-run"], capture_output=True,
                           text=True, timeout=60, cwd=SOURCE, stdin=subprocess.DEVNULL, env=env)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("kill, arc law, loss 0 %: 1 runs", r.stdout)


def main():
    global SOURCE
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument("--source", required=True, help="the project's source folder")
    args, rest = parser.parse_known_args()
    SOURCE = os.path.abspath(args.source)
    unittest.main(argv=[sys.argv[0]] + rest, verbosity=2)


if __name__ == "__main__":
    main()
