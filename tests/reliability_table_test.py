#!/usr/bin/python3
"""scripts/reliability.py: the tables' "median / worst" cells. A count's median over an even number of
runs may fall between two counts (3.5); it is never printed as a float of a whole count (4.0).

  tests/reliability_table_test.py SOURCE_DIR
"""
import importlib.util
import sys
from pathlib import Path

spec = importlib.util.spec_from_file_location("reliability", Path(sys.argv[1]) / "scripts" / "reliability.py")
reliability = importlib.util.module_from_spec(spec)
spec.loader.exec_module(reliability)

cases = [
    (([3, 5, 4, 4], reliability.fmt_count), "4 / 5"),
    (([3, 4], reliability.fmt_count), "3.5 / 4"),
    (([None, 0, 0], reliability.fmt_count), "0 / 0"),
    (([None], reliability.fmt_count), "-"),
    (([0.04, 0.2, 0.1], reliability.fmt_pct), "0.1 / 0.2"),
]
failed = [(args, want, reliability.med_worst(*args)) for args, want in cases if reliability.med_worst(*args) != want]
for args, want, got in failed:
    print("med_worst%r: %r, expected %r" % (args[:1], got, want))
print("reliability_table: %d of %d cells as expected" % (len(cases) - len(failed), len(cases)))
sys.exit(1 if failed else 0)
