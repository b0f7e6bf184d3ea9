#!/usr/bin/env python3
"""The layering rule of docs/ARCHITECTURE.md, checked on the source: which folder's C++ may include
which of the project's folders, which third-party headers it must not use, that no headers include
each other in a circle, and that the processes reach no Fast DDS header through the project's headers
either. A new include that crosses a layer fails this test; change the table here and in
docs/ARCHITECTURE.md together when a layer really moves.

Usage: layers_test.py SOURCE_DIR
"""
import os
import re
import sys

# The generated code of ROS 2's messages (idl/ros2: geometry_msgs/msg/Twist.h, ...: the vehicle interface's
# and the ROS 2 mirror's), which only common/dds includes.
ROS2_MSGS = {"builtin_interfaces", "std_msgs", "geometry_msgs", "nav_msgs", "sensor_msgs", "visualization_msgs"}
# folder -> project folders its code may include (besides its own). "shapeform" is the generated IDL
# code (shapeform/msg/*.h), which only common/dds and the benchmark include. A folder is a library (or
# several): its name is the first path component of an include ("core/params.hpp").
ALLOWED = {
    "common/core": set(),
    "common/shapes": {"core"},
    "common/util": set(),
    "common/protocol": {"core", "util"},
    "common/dds": {"core", "shapes", "util", "protocol", "shapeform"} | ROS2_MSGS,
    "common/config": {"core", "shapes", "util", "protocol"},
    "common/record": {"core", "config", "util", "viz"},  # run.mcap holds the scene drawn for Foxglove
    "common/app": {"config", "core", "util", "protocol"},
    "common/viz": {"core"},  # what Foxglove draws: pure, no DDS; the viewer, the supervisor and the simulator may use it
    "sim": {"core", "util", "app", "record", "viz"},
    "agent": {"core", "shapes", "protocol", "dds", "config", "util", "app"},
    "vehicle": {"core", "protocol", "dds", "config", "util", "app"},
    "supervisor": {"core", "shapes", "protocol", "dds", "config", "util", "app", "record", "viz"},
    "bench": {"core", "protocol", "dds", "config", "util", "app", "shapeform", "record"},
    "tools": {"core", "protocol", "dds", "config", "util", "app", "record"},  # shapeform_mcap reads record/mcap
    "view": {"core", "shapes", "protocol", "dds", "config", "util", "app", "record", "viz"},  # replay reads what record writes
}
# Third-party headers each folder may use: core is pure maths, and only common/dds sees Fast DDS.
FORBIDDEN_SYSTEM = {
    "common/core": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|nlohmann|CLI|muParser)"),
    "common/shapes": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|nlohmann|CLI)"),
    "common/util": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|Eigen)"),
    "common/protocol": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "common/config": re.compile(r"^(fastdds|fastrtps|fastcdr)"),
    "sim": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "common/app": re.compile(r"^(fastdds|fastrtps|fastcdr)"),
    "common/record": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "common/viz": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp|websocketpp|asio)"),
    "agent": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "vehicle": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "supervisor": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "tools": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
    "view": re.compile(r"^(fastdds|fastrtps|fastcdr|yaml-cpp)"),
}
# Libraries a folder's CMake targets must not link.
FORBIDDEN_LINKS = {
    "common/core": ("shapeform_", "yaml-cpp", "fastrtps", "fastcdr"),
    "common/protocol": ("shapeform_dds", "shapeform_config", "yaml-cpp", "fastrtps", "fastcdr"),
    "common/dds": ("shapeform_config", "yaml-cpp"),
    "common/util": ("shapeform_", "yaml-cpp", "fastrtps"),
    "common/viz": ("shapeform_dds", "shapeform_config", "yaml-cpp", "fastrtps", "fastcdr"),
}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]', re.M)
# The processes compile against the project's own API: no header of the project that their code includes
# may bring in Fast DDS, directly or through other headers (node.hpp, state_input.hpp, convert.hpp,
# topics.hpp, participant.hpp, ...). The generated messages (shapeform/msg/*.h: plain types on fastcdr)
# are not followed. bench/baseline.cpp is the raw Fast DDS baseline the benchmark compares with.
PROJECT_API_ONLY = ("agent", "vehicle", "supervisor", "view", "tools", "bench")
RAW_FASTDDS = {"bench/baseline.cpp"}
FASTDDS = re.compile(r"^(fastdds|fastrtps)/")


def unit_of(path):
    """A header and its source are one unit: "common/dds/topics"."""
    return os.path.splitext(path)[0]


def include_cycles(source):
    """Units of the project (a .hpp with its .cpp) whose headers include each other, directly or
    through others: every strongly connected component of more than one unit."""
    headers, edges = {}, {}
    for folder in ALLOWED:
        for root, _, files in os.walk(os.path.join(source, folder)):
            for name in files:
                if name.endswith((".cpp", ".hpp")):
                    rel = os.path.relpath(os.path.join(root, name), source)
                    if name.endswith(".hpp"):
                        top = folder.split("/")[-1]
                        headers[rel[rel.index(top + "/"):] if "/" in rel else rel] = unit_of(rel)
                        headers.setdefault(os.path.relpath(os.path.join(root, name), os.path.join(source, folder)),
                                           unit_of(rel))
                    edges.setdefault(unit_of(rel), set())
    for unit in list(edges):
        for ext in (".cpp", ".hpp"):
            path = os.path.join(source, unit + ext)
            if not os.path.exists(path):
                continue
            with open(path, errors="replace") as f:
                for kind, target in INCLUDE.findall(f.read()):
                    dep = headers.get(target) if kind == '"' else None
                    if dep is None and kind == '"':
                        local = os.path.normpath(os.path.join(os.path.dirname(unit), target))
                        dep = local if local in edges else None
                    if dep and dep != unit:
                        edges[unit].add(dep)
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):  # Tarjan's strongly connected components
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def includes_of(path):
    with open(path, errors="replace") as f:
        return INCLUDE.findall(f.read())


def resolve(source, including, target):
    """The project file that `#include "target"` in file `including` names, or None (generated code)."""
    for base in (os.path.dirname(including), os.path.join(source, "common"), source):
        path = os.path.normpath(os.path.join(base, target))
        if os.path.isfile(path):
            return path
    return None


def fastdds_path(source, header, memo):
    """[header, ..., "<fastdds/...>"]: how a project header brings in Fast DDS, or None."""
    if header not in memo:
        memo[header] = None  # an include circle ends here
        for kind, target in includes_of(header):
            if kind == "<" and FASTDDS.match(target):
                memo[header] = [os.path.relpath(header, source), "<%s>" % target]
                break
            dep = resolve(source, header, target) if kind == '"' else None
            rest = fastdds_path(source, dep, memo) if dep else None
            if rest:
                memo[header] = [os.path.relpath(header, source)] + rest
                break
    return memo[header]


def fastdds_leaks(source):
    """Problems: a file of a process folder that reaches Fast DDS through the project's headers (or,
    in bench, directly)."""
    problems, memo = [], {}
    for folder in PROJECT_API_ONLY:
        for root, _, files in os.walk(os.path.join(source, folder)):
            for name in sorted(files):
                path = os.path.join(root, name)
                where = os.path.relpath(path, source)
                if not name.endswith((".cpp", ".hpp", ".h")) or where in RAW_FASTDDS:
                    continue
                for kind, target in includes_of(path):
                    if kind == "<" and FASTDDS.match(target) and folder not in FORBIDDEN_SYSTEM:
                        problems.append("%s includes <%s>: %s uses the project's API only" % (where, target, folder))
                    dep = resolve(source, path, target) if kind == '"' else None
                    chain = fastdds_path(source, dep, memo) if dep else None
                    if chain:
                        problems.append("%s includes \"%s\", which brings in Fast DDS: %s" % (
                            where, target, " -> ".join(chain)))
    return problems


def main(source):
    problems = ["these files include each other's headers (directly or in a circle): %s" % ", ".join(c)
                for c in include_cycles(source)]
    problems += fastdds_leaks(source)
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
