#!/usr/bin/env python3
"""Writes a functional layer of N copies of robots/rover.ron: its nine modules, its
constraints, its battery and flight recorder and the connectors and priority that tie them
in, each copy with its own names (`rflex3`, `pack3`, `abort_blind_navigation3`, ...), one
tick for all, and deadlock freedom as the only property. The modules of a GenoM layer are
ordered by priorities (docs/genom.md), so N copies declare a long chain of them: N = 8
gives 72 modules and 1,596 declared priorities, N = 11 gives 99 modules. Deterministic.

    python3 bench/gen-rover-layer.py N > layer.ron && bip check layer.ron
"""
import os
import re
import sys

MODULES = ["rflex", "sick", "pom", "ndd", "aspect", "antenna", "battery", "heating", "camera"]
# the rover's own components and user connectors, renamed like its modules
OWN = MODULES + ["pack", "blackbox", "abort_blind_navigation"]
ROVER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "robots", "rover.ron")


def block(text, field):
    """The lines inside `    field: [` ... `    ],` (four spaces: a top-level field)."""
    m = re.search(r"^    %s: [\[{]\n(.*?)^    [\]}],\n" % field, text, re.M | re.S)
    if not m:
        sys.exit("robots/rover.ron has no top-level `%s`" % field)
    return m.group(1)


def renamed(text, k):
    """`text` with every name of OWN (alone, or before `_`, `.`) suffixed with k."""
    names = "|".join(sorted(OWN, key=len, reverse=True))
    return re.sub(r"(?<![A-Za-z0-9_])(%s)(?![A-Za-z0-9])" % names, r"\g<1>%d" % k, text)


def main():
    if len(sys.argv) != 2 or not sys.argv[1].isdigit() or int(sys.argv[1]) < 1:
        sys.exit("usage: gen-rover-layer.py N   (N >= 1 copies of the rover's layer)")
    n = int(sys.argv[1])
    rover = open(ROVER).read()
    modules = block(rover, "modules")
    constraints = block(rover, "constraints")
    components = block(rover, "components")
    connectors = block(rover, "connectors")
    priorities = block(rover, "priorities")
    atoms = block(rover, "atoms")
    constants = block(rover, "constants")
    # the tick is one connector for all: every copy's battery takes part in it
    tick = re.compile(r'^\s*\(name: "tick", ports: \["pack\.tick"\]\),\n', re.M)
    if not tick.search(connectors):
        sys.exit("robots/rover.ron's tick extension is not where this script expects it")
    connectors = tick.sub("", connectors)
    ticks = ", ".join('"pack%d.tick"' % k for k in range(n))
    out = ["// %d copies of robots/rover.ron's functional layer. Written by" % n,
           "// bench/gen-rover-layer.py; do not edit.",
           "System(", '    name: "rover_layer_%d",' % n, "    tick_ms: 100",
           "    constants: {", constants.rstrip("\n"), "    },", "    modules: ["]
    out += [renamed(modules, k).rstrip("\n") for k in range(n)]
    out += ["    ],", "    constraints: ["]
    out += [renamed(constraints, k).rstrip("\n") for k in range(n)]
    out += ["    ],", "    atoms: {", atoms.rstrip("\n"), "    },", "    components: ["]
    out += [renamed(components, k).rstrip("\n") for k in range(n)]
    out += ["    ],", "    connectors: [", '        (name: "tick", ports: [%s]),' % ticks]
    out += [renamed(connectors, k).rstrip("\n") for k in range(n)]
    out += ["    ],", "    priorities: ["]
    out += [renamed(priorities, k).rstrip("\n") for k in range(n)]
    out += ["    ],", "    properties: [DeadlockFree],", ")"]
    # `tick_ms: 100` needs its comma
    out[4] += ","
    print("\n".join(out))


main()
