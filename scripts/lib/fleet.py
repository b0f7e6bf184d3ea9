#!/usr/bin/python3
"""Fleet files (config/fleets/*.yaml, described in config/fleets/README.md): which host runs which agents
and the supervisor, and how a command runs on each host. The one reader of the format: it validates a
file and prints the plan scripts/launch_swarm.sh --fleet follows.

    fleet.py FILE [--prog NAME]

Prints one line per fact, fields separated by single spaces (no field holds a space):

    fleet NAME AGENTS                   the file's base name, the number of agents (ids 0..AGENTS-1)
    lab NAME HOSTS SUBNET               only when the fleet asks the launcher to make test hosts
    discovery KIND A,B,...              the file's discovery (multicast or unicast) and every host's
                                        address: the peers of unicast discovery
    host NAME ADDRESS KIND TARGET       KIND netns (TARGET the namespace), ssh (TARGET [user@]host) or
                                        local (TARGET -)
    agent ID HOST                       one line per agent id, in order
    supervisor HOST

A bad file is one line on stderr, `NAME: FILE: KEY: what is wrong` (NAME from --prog, default fleet), and
exit status 2. Needs python3-yaml (scripts/install_deps.sh).
"""
import ipaddress
import os
import re
import sys

import yaml

SCHEMA_VERSION = 1
TOP_KEYS = ("schema_version", "lab", "hosts", "supervisor", "transport")
LAB_KEYS = ("name", "hosts", "subnet")
HOST_KEYS = ("name", "address", "run", "agents")
TRANSPORT_KEYS = ("discovery",)
DISCOVERY = ("multicast", "unicast")
MAX_AGENTS = 1000
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,31}$")
NETNS_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
SSH_RE = re.compile(r"^([A-Za-z0-9_][A-Za-z0-9_.-]{0,31}@)?[A-Za-z0-9][A-Za-z0-9_.:-]{0,252}$")
LAB_RE = re.compile(r"^[a-z0-9]{1,8}$")  # as scripts/netlab.sh accepts
RANGE_RE = re.compile(r"^\s*(\d+)\s*-\s*(\d+)\s*$")


class FleetError(Exception):
    def __init__(self, key, message):
        super().__init__("%s: %s" % (key, message))


class _Loader(yaml.SafeLoader):
    """SafeLoader that refuses duplicate keys, as the config loader does (a typo never passes silently)."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if key in seen:
                raise FleetError(key, "duplicate key (line %d)" % (key_node.start_mark.line + 1))
            seen.add(key)
        return super().construct_mapping(node, deep)


def _brief(value):
    text = repr(value) if not isinstance(value, str) else "'%s'" % value
    return text if len(text) <= 60 else text[:57] + "..."


def _mapping(value, key, allowed):
    key = key or "(the file)"
    if not isinstance(value, dict):
        raise FleetError(key, "expected a mapping with keys %s, got %s" % (", ".join(allowed), _brief(value)))
    for k in value:
        if k not in allowed:
            raise FleetError(k if key == "(the file)" else "%s.%s" % (key, k),
                             "unknown key (known: %s)" % ", ".join(allowed))
    return value


def _required(mapping, key, where):
    if key not in mapping or mapping[key] is None:
        raise FleetError("%s.%s" % (where, key) if where else key, "required")
    return mapping[key]


def _integer(value, key, low, high):
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise FleetError(key, "expected an integer %d..%d, got %s" % (low, high, _brief(value)))
    return value


def _address(value, key):
    try:
        addr = ipaddress.IPv4Address(value) if isinstance(value, str) else None
    except ValueError:
        addr = None
    if addr is None or addr.is_unspecified or addr.is_multicast or str(addr) != value:
        raise FleetError(key, "expected a host's IPv4 address (dotted quad), got %s" % _brief(value))
    return value


def _agent_ids(value, key):
    """`agents:` as an id, "A-B", or a list of these -> list of ids in order."""
    items = value if isinstance(value, list) else [value]
    ids = []
    for item in items:
        if isinstance(item, int) and not isinstance(item, bool):
            first = last = item
        elif isinstance(item, str) and RANGE_RE.match(item):
            first, last = (int(x) for x in RANGE_RE.match(item).groups())
        else:
            raise FleetError(key, "expected an agent id, a range A-B or a list of these, got %s" % _brief(item))
        if not 0 <= first <= last < MAX_AGENTS:
            raise FleetError(key, "expected ids in 0..%d, the range increasing, got %s" % (MAX_AGENTS - 1, _brief(item)))
        ids.extend(range(first, last + 1))
    return ids


def _run(value, key):
    """`run:` -> (kind, target)."""
    words = value.split() if isinstance(value, str) else []
    if words == ["local"]:
        return "local", "-"
    if len(words) == 2 and words[0] == "netns" and NETNS_RE.match(words[1]):
        return "netns", words[1]
    if len(words) == 2 and words[0] == "ssh" and SSH_RE.match(words[1]):
        return "ssh", words[1]
    raise FleetError(key, "expected 'netns NAME', 'ssh [USER@]HOST' or 'local', got %s" % _brief(value))


def _lab(value):
    lab = _mapping(value, "lab", LAB_KEYS)
    name = _required(lab, "name", "lab")
    if not isinstance(name, str) or not LAB_RE.match(name):
        raise FleetError("lab.name", "expected 1..8 lowercase letters or digits, got %s" % _brief(name))
    hosts = _integer(_required(lab, "hosts", "lab"), "lab.hosts", 1, 32)
    subnet = _required(lab, "subnet", "lab")
    m = re.match(r"^10\.(\d{1,3})\.(\d{1,3})$", subnet) if isinstance(subnet, str) else None
    if not m or int(m.group(1)) > 255 or int(m.group(2)) > 254:
        raise FleetError("lab.subnet", "expected 10.B.C (B <= 255, C <= 254), got %s" % _brief(subnet))
    return {"name": name, "hosts": hosts, "subnet": subnet}


def parse(text):
    """The plan of a fleet file's text: {lab, hosts: [{name, address, kind, target, agents}], supervisor,
    discovery, agents: N}. Raises FleetError naming the key."""
    try:
        doc = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        raise FleetError("yaml", "not valid YAML%s: %s" % (" (line %d)" % (mark.line + 1) if mark else "",
                                                          getattr(e, "problem", None) or e))
    top = _mapping(doc, "", TOP_KEYS)
    if top.get("schema_version") != SCHEMA_VERSION:
        raise FleetError("schema_version", "required, and must be %d (got %s)" % (SCHEMA_VERSION,
                                                                                 _brief(top.get("schema_version"))))
    lab = _lab(top["lab"]) if top.get("lab") is not None else None
    transport = _mapping(top.get("transport") or {}, "transport", TRANSPORT_KEYS)
    discovery = transport.get("discovery", "multicast")
    if discovery not in DISCOVERY:
        raise FleetError("transport.discovery", "expected %s, got %s" % (" or ".join(DISCOVERY), _brief(discovery)))

    raw_hosts = _required(top, "hosts", "")
    if not isinstance(raw_hosts, list) or not raw_hosts:
        raise FleetError("hosts", "expected a list of hosts, got %s" % _brief(raw_hosts))
    hosts, names, addresses, owner = [], {}, {}, {}
    for k, raw in enumerate(raw_hosts):
        where = "hosts[%d]" % k
        if isinstance(raw, dict) and isinstance(raw.get("name"), str) and NAME_RE.match(raw["name"]):
            where += " (%s)" % raw["name"]
        h = _mapping(raw, where, HOST_KEYS)
        name = _required(h, "name", where)
        if not isinstance(name, str) or not NAME_RE.match(name):
            raise FleetError(where + ".name", "expected a name of letters, digits, _ and -, got %s" % _brief(name))
        if name in names:
            raise FleetError(where + ".name", "host '%s' is also hosts[%d]" % (name, names[name]))
        names[name] = k
        address = _address(_required(h, "address", where), where + ".address")
        if address in addresses:
            raise FleetError(where + ".address", "%s is also the address of host '%s'" % (address, addresses[address]))
        addresses[address] = name
        kind, target = _run(_required(h, "run", where), where + ".run")
        if lab and kind == "netns" and target.startswith("sf-%s-h" % lab["name"]):
            m = re.match(r"^sf-%s-h(\d+)$" % lab["name"], target)
            if not m or not 1 <= int(m.group(1)) <= lab["hosts"]:
                raise FleetError(where + ".run", "the lab '%s' has hosts sf-%s-h1..h%d, not %s"
                                 % (lab["name"], lab["name"], lab["hosts"], target))
            expected = "%s.%s" % (lab["subnet"], m.group(1))
            if address != expected:
                raise FleetError(where + ".address", "%s of the lab has the address %s, got %s"
                                 % (target, expected, address))
        ids = _agent_ids(h["agents"], where + ".agents") if h.get("agents") is not None else []
        for i in ids:
            if i in owner:
                raise FleetError(where + ".agents", "agent %d runs on host '%s' too" % (i, owner[i]))
            owner[i] = name
        hosts.append({"name": name, "address": address, "kind": kind, "target": target, "agents": ids})

    n = len(owner)
    if n == 0:
        raise FleetError("hosts", "no host runs an agent (give a host `agents: 0-11`)")
    missing = [i for i in range(n) if i not in owner]
    if missing:
        raise FleetError("hosts[].agents", "the %d agents must be ids 0..%d, each on one host; missing %s"
                         % (n, n - 1, _id_list(missing)))
    supervisor = _required(top, "supervisor", "")
    if supervisor not in names:
        raise FleetError("supervisor", "expected the name of a host (%s), got %s"
                         % (", ".join(names), _brief(supervisor)))
    return {"lab": lab, "hosts": hosts, "supervisor": supervisor, "discovery": discovery, "agents": n,
            "owner": owner}


def _id_list(ids):
    text = ", ".join(str(i) for i in ids[:8])
    return text + (" ... (%d in all)" % len(ids) if len(ids) > 8 else "")


def plan_lines(name, plan):
    lines = ["fleet %s %d" % (name, plan["agents"])]
    if plan["lab"]:
        lines.append("lab %(name)s %(hosts)d %(subnet)s" % plan["lab"])
    lines.append("discovery %s %s" % (plan["discovery"], ",".join(h["address"] for h in plan["hosts"])))
    lines += ["host %(name)s %(address)s %(kind)s %(target)s" % h for h in plan["hosts"]]
    lines += ["agent %d %s" % (i, plan["owner"][i]) for i in range(plan["agents"])]
    lines.append("supervisor " + plan["supervisor"])
    return lines


def main(argv):
    prog, args = "fleet", list(argv)
    if args[:1] in (["-h"], ["--help"]):
        sys.stdout.write(__doc__)
        return 0
    if len(args) == 3 and args[1] == "--prog":
        prog = args.pop(2)
        args.pop(1)
    if len(args) != 1:
        sys.stderr.write("fleet: usage: fleet.py FILE [--prog NAME] (see --help)\n")
        return 2
    path = args[0]
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except (OSError, UnicodeDecodeError) as e:
        sys.stderr.write("%s: %s: cannot read: %s\n" % (prog, path, getattr(e, "strerror", None) or e))
        return 2
    try:
        plan = parse(text)
    except FleetError as e:
        sys.stderr.write("%s: %s: %s\n" % (prog, path, e))
        return 2
    name = re.sub(r"\.ya?ml$", "", os.path.basename(path))
    name = re.sub(r"[^A-Za-z0-9_-]", "_", name) or "fleet"
    sys.stdout.write("\n".join(plan_lines(name, plan)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
