#!/usr/bin/env bash
# Load time of `bip check` on a model with N components and N connectors (the shape of
# bip-model's huge_file_loads test). By hand, not in CI:  bench/load.sh [N...]
source "$(dirname "$0")/common.sh"
sizes=("$@")
((${#sizes[@]})) || sizes=(50000 100000)
for n in "${sizes[@]}"; do
    f="$WORK/huge-$n.ron"
    python3 - "$n" > "$f" <<'PY'
import sys
n = int(sys.argv[1])
print('System(name: "huge", atoms: {"Fork": Atom(locations: ["free", "taken"], initial: "free",')
print('  ports: ["take", "release"], transitions: [(from: "free", port: "take", to: "taken"),')
print('  (from: "taken", port: "release", to: "free")])},')
print('components: [')
for i in range(n):
    print(f'(name: "f{i}", atom: "Fork"),')
print('], connectors: [')
for i in range(n):
    print(f'(name: "c{i}", ports: ["f{i}.take", "f{(i + 1) % n}.release"]),')
print('])')
PY
    size=$(du -h "$f" | cut -f1)
    /usr/bin/time -f "N=$n ($size): %e s, peak %M KiB" "$BIP" check "$f" > /dev/null
done
