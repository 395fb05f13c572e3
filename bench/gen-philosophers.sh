#!/usr/bin/env bash
# Writes robots/bench/philosophers-{100,1000,10000}.ron: the deadlock-free (asymmetric)
# dining philosophers of robots/philosophers-asymmetric.ron with N philosophers and N forks,
# deadlock freedom as the only property (the symbolic benchmark of docs/performance.md).
#
#   bench/gen-philosophers.sh && bip verify robots/bench/philosophers-1000.ron --method symbolic
set -euo pipefail
cd "$(dirname "$0")/.."
for n in 100 1000 10000; do
    out=robots/bench/philosophers-$n.ron
    {
        echo "// Benchmark: robots/philosophers-asymmetric.ron with N = $n, deadlock freedom only."
        echo "// Written by bench/gen-philosophers.sh; do not edit."
        sed -e "s/\"N\": 5/\"N\": $n/" robots/philosophers-asymmetric.ron
    } | python3 -c '
import re, sys
s = sys.stdin.read()
s = re.sub(r"properties: \[.*?\n    \],", "properties: [DeadlockFree],", s, flags=re.S)
sys.stdout.write(s)' > "$out"
    echo "$out"
done
