#!/usr/bin/env python3
"""Writes robots/bench/dala-module.ron: one GenoM module the size of DALA's largest
(RFLEX: 56 components, 227 interactions in D-Finder's published table).

The module has eight execution tasks of different periods and 44 activity services of
three shapes (a one-codel activity, a start/work loop that publishes a port, and a
start/work/stop activity that can fail), plus function services that interrupt some of
them; a third of the activities wait for `Init` (`after`), some interrupt a sibling. It
expands (docs/genom.md) into about 50 components and 200 interactions. Deterministic:
running it again writes the same file.

    python3 bench/gen-dala.py && bip check robots/bench/dala-module.ron
"""
import os

TASKS = [("t%d" % i, 1 + i % 3) for i in range(8)]
ACTIVITIES = 44

services = ['                (name: "Init", kind: Function),']
ports = []
for a in range(ACTIVITIES):
    task = TASKS[a % len(TASKS)][0]
    name = "A%02d" % a
    extra = []
    if a % 3 == 0:
        extra.append('after: ["Init"]')
    if a % 7 == 3 and a > 0:
        extra.append('interrupts: ["A%02d"]' % (a - 1))
    extra = "".join(" " + e + "," for e in extra)
    shape = a % 3
    if shape == 0:
        codels = '(state: "start", yields: ["ether"])'
    elif shape == 1:
        port = "p%02d" % a
        ports.append('(name: "%s")' % port)
        codels = (
            '(state: "start", yields: ["pause::work"]),\n'
            '                     (state: "work", yields: ["pause::work", "ether"], writes: ["%s"])'
            % port
        )
    else:
        codels = (
            '(state: "start", yields: ["pause::work"]),\n'
            '                     (state: "work", yields: ["pause::work", "stop"], throws: ["e_fail"]),\n'
            '                     (state: "stop", yields: ["ether"])'
        )
    services.append(
        '                (name: "%s", kind: Activity, task: "%s",%s\n'
        "                 codels: [\n"
        "                     %s,\n"
        "                 ]),"
        % (name, task, extra, codels)
    )
for k in range(0, ACTIVITIES, 5):
    services.append(
        '                (name: "Stop%02d", kind: Function, interrupts: ["A%02d"]),' % (k, k)
    )

text = """// Benchmark: one GenoM module the size of DALA's largest (RFLEX: 56 components, 227
// interactions in D-Finder's published table). Written by bench/gen-dala.py; do not edit.
//
//   bip check robots/bench/dala-module.ron
//   bip verify robots/bench/dala-module.ron --method symbolic
System(
    name: "dala_module",
    tick_ms: 100,
    modules: [
        (
            name: "rflex",
            doc: "a DALA-scale module: %d activities on %d tasks",
            tasks: [%s],
            ports: [%s],
            services: [
%s
            ],
        ),
    ],
    properties: [DeadlockFree],
)
""" % (
    ACTIVITIES,
    len(TASKS),
    ", ".join('(name: "%s", period: %d)' % t for t in TASKS),
    ", ".join(ports),
    "\n".join(services),
)

out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "robots", "bench", "dala-module.ron")
with open(out, "w") as f:
    f.write(text)
print(os.path.normpath(out))
