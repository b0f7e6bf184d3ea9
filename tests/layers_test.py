#!/usr/bin/env python3
"""The layering rule of docs/ARCHITECTURE.md, checked on the source: which folder's C++ may include
which of the project's folders. A new include that crosses a layer fails this test; change the table
here and in docs/ARCHITECTURE.md together when a layer really moves.

Usage: layers_test.py SOURCE_DIR
"""
import os
import re
import sys

# folder -> project folders its code may include (besides its own). "shapeform" is the generated IDL
# code (shapeform/msg/*.h), which only common/dds and the benchmark include.
ALLOWED = {
    "common/core": set(),
    "common/shapes": {"core"},
    "common/util": set(),
    "common/dds": {"core", "shapes", "util", "shapeform"},
    "common/config": {"core", "shapes", "util", "dds/transport.hpp"},
    "common/sim": {"core", "util", "app", "record"},
    "common/record": {"core", "config", "util"},
    "common/app": {"config", "core", "util", "dds/transport.hpp"},
    "agent": {"core", "shapes", "dds", "config", "util", "app"},
    "supervisor": {"core", "shapes", "dds", "config", "util", "app", "record"},
    "bench": {"core", "dds", "config", "util", "app", "shapeform"},
    "tools": {"core", "dds", "config", "util", "app"},
    "view": {"core", "shapes", "dds", "config", "util", "app", "record"},  # replay reads what record writes
}
# Third-party headers each folder may use: core is pure maths, and only common/dds sees Fast DDS.
FORBIDDEN_SYSTEM = {
    "common/core": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|nlohmann|CLI|muParser)"),
    "common/shapes": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|nlohmann|CLI)"),
    "common/util": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|Eigen)"),
    "common/config": re.compile(r"^(fastdds|fastrtps|fastcdr)"),
    "common/sim": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "common/app": re.compile(r"^(fastdds|fastrtps|fastcdr)"),
    "common/record": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "agent": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "supervisor": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "tools": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "view": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
}
# Libraries a folder's CMake targets must not link.
FORBIDDEN_LINKS = {
    "common/core": ("shapeform_", "yaml-cpp", "fastrtps", "fastcdr"),
    "common/dds": ("shapeform_config", "yaml-cpp"),
    "common/util": ("shapeform_", "yaml-cpp", "fastrtps"),
}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)


def main(source):
    problems = []
    for folder, allowed in ALLOWED.items():
        own = os.path.basename(folder)
        for root, _, files in os.walk(os.path.join(source, folder)):
            for name in sorted(files):
                if not name.endswith((".cpp", ".hpp", ".h")):
                    continue
                path = os.path.join(root, name)
                with open(path, errors="replace") as f:
                    text = f.read()
                for kind, target in INCLUDE.findall(text):
                    where = os.path.relpath(path, source)
                    top = target.split("/")[0]
                    if kind == '"' and "/" in target and top != own and top not in allowed \
                            and target not in allowed:
                        problems.append("%s includes \"%s\": %s may include only %s" % (
                            where, target, folder, ", ".join(sorted(allowed | {own}))))
                    banned = FORBIDDEN_SYSTEM.get(folder)
                    if kind == "<" and banned and banned.match(target):
                        problems.append("%s includes <%s>, which %s must not use" % (where, target, folder))
    link = re.compile(r"target_link_libraries\(\s*(\S+)([^)]*)\)", re.S)
    for folder, banned in FORBIDDEN_LINKS.items():
        with open(os.path.join(source, folder, "CMakeLists.txt")) as f:
            for target, deps in link.findall(f.read()):
                for dep in deps.split():
                    if dep.startswith(banned) and dep != "shapeform_warnings":
                        problems.append("%s/CMakeLists.txt: %s links %s" % (folder, target, dep))
    for p in problems:
        print(p)
    print("%d layering problem(s)" % len(problems))
    return 1 if problems else 0


if __name__ == "__main__":
    if len(sys.argv) != 2 or sys.argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        sys.exit(0 if len(sys.argv) == 2 else 2)
    sys.exit(main(sys.argv[1]))
