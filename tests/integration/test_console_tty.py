#!/usr/bin/env python3
"""The supervisor's console in a real terminal: the supervisor runs alone (no agent is needed) with a
pseudo-terminal as its controlling terminal, stdin, stdout and stderr, so Ctrl-C is the terminal's
interrupt key (SIGINT to the foreground process group), exactly as when an operator types it. What it
draws is fed through a small VT100 screen model, and the tests check the screen an operator sees:

- half a command + Ctrl-C clears the line, and the supervisor runs on;
- `wait converged timeout=600` + Ctrl-C cancels the wait with a message and the prompt returns;
- with `progress every 0.2`, a line typed slowly is never broken by the progress lines (they appear
  above it, and the line stays whole on the prompt row);
- Tab completes; history is kept in a file between runs (Up recalls the last run's command);
- Ctrl-D on an empty line ends it with status 0; two Ctrl-C within 1 s end it with status 130.

Each program also answers --version.
"""

import fcntl
import os
import re
import select
import signal
import struct
import subprocess
import sys
import termios
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from harness import bin_path  # noqa: E402

ROWS, COLS = 40, 120
PROMPT = "shapeform> "
CSI = re.compile(r"\x1b\[([?0-9;]*)([@-~])")


class Screen:
    """Enough of a VT100 to replay what libedit and the supervisor write: printable characters with
    autowrap, CR, LF, BS, and the CSI cursor moves and erases; other sequences are ignored."""

    def __init__(self, rows=ROWS, cols=COLS):
        self.rows, self.cols = rows, cols
        self.lines = [[" "] * cols for _ in range(rows)]
        self.r = self.c = 0
        self.pending = ""

    def _scroll(self):
        self.lines.pop(0)
        self.lines.append([" "] * self.cols)

    def _newline(self):
        if self.r == self.rows - 1:
            self._scroll()
        else:
            self.r += 1

    def feed(self, text):
        text = self.pending + text
        self.pending = ""
        i = 0
        while i < len(text):
            ch = text[i]
            if ch == "\x1b":
                m = CSI.match(text, i)
                if m:
                    self._csi(m.group(1), m.group(2))
                    i = m.end()
                    continue
                if i + 1 >= len(text) or (text[i + 1] == "[" and not CSI.match(text + "m", i)):
                    self.pending = text[i:]  # an escape sequence cut in two
                    return
                if text[i + 1] in "()":  # ESC ( B: a character set
                    if i + 2 >= len(text):
                        self.pending = text[i:]
                        return
                    i += 3
                    continue
                i += 2  # ESC = , ESC > , ...
                continue
            if ch == "\r":
                self.c = 0
            elif ch == "\n":
                self._newline()
            elif ch == "\b":
                self.c = max(0, self.c - 1)
            elif ch >= " ":
                if self.c >= self.cols:
                    self.c = 0
                    self._newline()
                self.lines[self.r][self.c] = ch
                self.c += 1
            i += 1

    def _csi(self, params, final):
        if params.startswith("?"):
            return
        nums = [int(p) if p else 0 for p in params.split(";")] if params else []
        n = nums[0] if nums and nums[0] > 0 else 1
        if final == "A":
            self.r = max(0, self.r - n)
        elif final == "B":
            self.r = min(self.rows - 1, self.r + n)
        elif final == "C":
            self.c = min(self.cols - 1, self.c + n)
        elif final == "D":
            self.c = max(0, self.c - n)
        elif final == "G":
            self.c = min(self.cols - 1, n - 1)
        elif final in "Hf":
            self.r = min(self.rows - 1, (nums[0] if nums and nums[0] else 1) - 1)
            self.c = min(self.cols - 1, (nums[1] if len(nums) > 1 and nums[1] else 1) - 1)
        elif final == "J":
            mode = nums[0] if nums else 0
            if mode == 0:
                self.lines[self.r][self.c:] = [" "] * (self.cols - self.c)
                for r in range(self.r + 1, self.rows):
                    self.lines[r] = [" "] * self.cols
            elif mode == 2:
                self.lines = [[" "] * self.cols for _ in range(self.rows)]
        elif final == "K":
            mode = nums[0] if nums else 0
            if mode == 0:
                self.lines[self.r][self.c:] = [" "] * (self.cols - self.c)
            elif mode == 1:
                self.lines[self.r][:self.c + 1] = [" "] * (self.c + 1)
            else:
                self.lines[self.r] = [" "] * self.cols
        elif final == "P":  # delete characters
            row = self.lines[self.r]
            del row[self.c:self.c + n]
            row.extend([" "] * n)
        elif final == "@":  # insert blanks
            row = self.lines[self.r]
            row[self.c:self.c] = [" "] * n
            del row[self.cols:]

    def text(self):
        return ["".join(line).rstrip() for line in self.lines]

    def cursor_line(self):
        return "".join(self.lines[self.r]).rstrip()


class Tty:
    """The supervisor on a pseudo-terminal that is its controlling terminal."""

    def __init__(self, argv, env, log_path):
        self.master, slave = os.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", ROWS, COLS, 0, 0))

        def make_controlling_terminal():
            os.setsid()
            fcntl.ioctl(0, termios.TIOCSCTTY, 0)

        self.proc = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, env=env, close_fds=True,
                                     preexec_fn=make_controlling_terminal)
        os.close(slave)
        self.screen = Screen()
        self.raw = ""
        self.log = open(log_path, "w")

    def read(self, timeout=0.05):
        ready, _, _ = select.select([self.master], [], [], timeout)
        if not ready:
            return
        try:
            data = os.read(self.master, 65536).decode(errors="replace")
        except OSError:  # EIO: every slave descriptor closed (the process ended)
            time.sleep(timeout)
            return
        self.raw += data
        self.log.write(data)
        self.log.flush()
        self.screen.feed(data)

    def until(self, what, predicate, timeout=10.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.read()
            if predicate():
                return
        raise AssertionError("timed out waiting for %s; screen:\n%s" % (what, "\n".join(self.screen.text())))

    def until_cursor_line(self, text, timeout=10.0):
        """The row of the cursor reads `text` (trailing blanks aside)."""
        self.until("cursor line %r" % text, lambda: self.screen.cursor_line() == text.rstrip(), timeout)

    def until_raw_count(self, text, n, timeout=10.0):
        """`text` has been written at least n times in all."""
        self.until("%r written %d times" % (text, n), lambda: self.raw.count(text) >= n, timeout)

    def until_screen_has(self, text, timeout=10.0):
        self.until("%r on the screen" % text, lambda: any(text in line for line in self.screen.text()), timeout)

    def keys(self, text, line=None, screen=None):
        """Types text, then waits until the cursor row reads `line` and/or `screen` is on the screen."""
        self.type(text)
        if screen is not None:
            self.until_screen_has(screen)
        if line is not None:
            self.until_cursor_line(line)

    def type(self, text, pause=0.0):
        for ch in text:
            os.write(self.master, ch.encode())
            if pause:
                end = time.monotonic() + pause
                while time.monotonic() < end:
                    self.read(min(0.02, max(0.0, end - time.monotonic())))

    def wait_exit(self, timeout=20.0):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.read()
            rc = self.proc.poll()
            if rc is not None:
                return rc
        raise AssertionError("the supervisor did not exit; screen:\n%s" % "\n".join(self.screen.text()))

    def close(self):
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        os.close(self.master)
        self.log.close()


class ConsoleTtyTest(harness.SwarmTestCase):
    def start_tty(self, name):
        home = os.path.join(self.run_dir, "home")
        os.makedirs(home, exist_ok=True)
        env = {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), "HOME": home, "TERM": "xterm", "LANG": "C.UTF-8"}
        argv = [bin_path("shapeform_supervisor"), "--domain", str(self.domain)]
        tty = Tty(argv, env, os.path.join(self.run_dir, name + ".out"))
        self.ttys.append(tty)
        tty.until_cursor_line(PROMPT.rstrip())
        return tty

    def setUp(self):
        super().setUp()
        self.ttys = []

    def tearDown(self):
        for tty in self.ttys:
            tty.close()
        super().tearDown()

    def assert_alive(self, tty):
        self.assertIsNone(tty.proc.poll(), "the supervisor ended")
        answers = tty.raw.count("(no agent heard yet)")
        tty.type("status\r")  # it still answers
        tty.until_raw_count("(no agent heard yet)", answers + 1)
        tty.until_cursor_line(PROMPT)

    def test_console_in_a_terminal(self):
        tty = self.start_tty("first")

        # Half a command, Ctrl-C: the line is cleared, a fresh prompt, the supervisor runs on.
        tty.type("shape cir")
        tty.until_cursor_line(PROMPT + "shape cir")
        tty.type("\x03")
        tty.until_cursor_line(PROMPT.rstrip())
        self.assert_alive(tty)

        # A wait that would last 600 s, Ctrl-C: cancelled with a message, the prompt returns.
        tty.type("wait converged timeout=600\r")
        time.sleep(0.5)
        tty.read()
        self.assertNotEqual(tty.screen.cursor_line(), PROMPT.rstrip(), "no prompt while the wait runs")
        tty.type("\x03")
        tty.until_screen_has("wait converged: cancelled (Ctrl-C)")
        tty.until_cursor_line(PROMPT.rstrip())
        self.assert_alive(tty)

        # Progress every 0.2 s while a line is typed slowly: the line stays whole on the prompt row.
        tty.type("progress every 0.2\r")
        tty.until_cursor_line(PROMPT.rstrip())
        typed = "shape circle r=4 cx=1"
        progress_before = tty.raw.count("[supervisor] t=")
        tty.type(typed, pause=0.08)
        tty.until_cursor_line(PROMPT + typed)
        screen = tty.screen.text()
        self.assertGreaterEqual(tty.raw.count("[supervisor] t=") - progress_before, 5,
                                "progress lines were printed while typing")
        for line in screen:
            if "[supervisor] t=" in line:
                self.assertTrue(line.startswith("[supervisor] t="), "a progress line starts its row: %r" % line)
                self.assertNotIn(PROMPT, line)
            if PROMPT in line:
                self.assertTrue(line.startswith(PROMPT), "the prompt starts its row: %r" % line)
        self.assertEqual([l for l in screen if l.startswith(PROMPT + "shape circle")], [PROMPT + typed],
                         "the typed line appears once, whole")
        tty.type("\r")
        tty.until_screen_has("epoch 1: circle r=4")
        tty.type("progress off\r")
        tty.until_cursor_line(PROMPT.rstrip())

        # Tab completes a command word and a parameter name.
        tty.keys("sha\t", line=PROMPT + "shape ")
        tty.keys("ell\t", line=PROMPT + "shape ellipse ")
        tty.keys("\x03", line=PROMPT.rstrip())

        # `show`, `metrics`, `record stop` answer at the terminal too.
        tty.keys("show\r", screen="epoch 1, published by this supervisor")
        tty.keys("record stop\r", screen="record stop: nothing is being recorded", line=PROMPT.rstrip())

        # Ctrl-D on an empty line: status 0.
        tty.type("\x04")
        self.assertEqual(tty.wait_exit(), 0)

        # A second run: Up recalls the last command of the first (history file), then two Ctrl-C
        # within a second on an empty line: status 130.
        tty = self.start_tty("second")
        self.assertTrue(os.path.exists(os.path.join(self.run_dir, "home", ".shapeform_history")))
        tty.keys("\x1b[A", line=PROMPT + "record stop")
        tty.keys("\x03", line=PROMPT.rstrip())
        tty.keys("\x03", screen="Ctrl-C again within 1 s")
        tty.type("\x03")
        self.assertEqual(tty.wait_exit(), 130)

    def test_every_program_answers_version(self):
        programs = sorted(f for f in os.listdir(os.path.dirname(bin_path("x"))) if f.startswith("shapeform_"))
        self.assertGreaterEqual(len(programs), 10, programs)  # agents, supervisor, sim, bench, tools, doc
        for exe in programs:
            with self.subTest(exe=exe):
                r = subprocess.run([bin_path(exe), "--version"], capture_output=True, text=True, timeout=30)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertRegex(r.stdout, r"^%s \d+\.\d+\.\d+( \(git \S+\))?\n$" % exe)


if __name__ == "__main__":
    harness.main()
