#!/usr/bin/env bash
# Runs `bip verify` and SPIN on the same models and prints states, time and memory side by
# side. By hand, not in CI:  bench/compare.sh [quick]
#
# SPIN gets `bip export --promela` of each model, compiled twice:
#   spin -o2: no dead-variable elimination, so SPIN's states are exactly bip's;
#   -O2 -DSAFETY -DNOREDUCE (no partial-order reduction) and SPIN's default (with it; one
#   process, so it reduces nothing here), both with -DMEMLIM large enough.
# bip runs with one worker and with two. Wall time and peak RSS from /usr/bin/time.
source "$(dirname "$0")/common.sh"

models=()
gen() { # name template constant value
    local out="$WORK/$1.ron"
    sed "s/\"$3\": [0-9]*/\"$3\": $4/" "$2" > "$out"
    # deadlock freedom only: the property SPIN checks too
    python3 - "$out" <<'PY'
import re, sys
p = sys.argv[1]; s = open(p).read()
s = re.sub(r'properties: \[.*?\n    \],', 'properties: [DeadlockFree],', s, flags=re.S)
open(p, 'w').write(s)
PY
    models+=("$out")
}
if [[ "${1:-}" == quick ]]; then
    gen phil-10 robots/philosophers.ron N 10
    gen token-6 robots/bench/token-ring.ron N 6
else
    for n in 4 8 12 14 16; do gen "phil-$n" robots/philosophers.ron N "$n"; done
    for n in 12 16; do gen "aphil-$n" robots/philosophers-asymmetric.ron N "$n"; done
    for n in 8 10; do gen "token-$n" robots/bench/token-ring.ron N "$n"; done
    for c in 6 10; do gen "buffers-$c" robots/bench/buffers.ron CAP "$c"; done
fi

measure() { # label command...: prints "seconds peak-KiB" of the command
    /usr/bin/time -f "%e %M" -o "$WORK/time" "$@" > "$WORK/out" 2>&1 || true
    tail -n 1 "$WORK/time"
}

printf "%-10s %-16s %12s %9s %12s %9s %9s\n" model tool states seconds states/s "peak MiB" "B/state"
for m in "${models[@]}"; do
    name=$(basename "$m" .ron)
    for jobs in 1 2; do
        read -r secs kib < <(measure "$BIP" verify "$m" --method explicit -j "$jobs" --format json)
        states=$(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d["stats"]["states"], d["stats"]["bytes_per_state"], d["stats"]["seconds"])' "$WORK/out")
        read -r n bps inner <<<"$states"
        printf "%-10s %-16s %12s %9.2f %12.0f %9.1f %9.1f\n" "$name" "bip -j$jobs" "$n" "$inner" "$(python3 -c "print($n/max($inner,1e-9))")" "$(python3 -c "print($kib/1024)")" "$bps"
    done
    "$BIP" export "$m" --promela "$WORK/m.pml"
    (cd "$WORK" && spin -o2 -a m.pml > /dev/null)
    for variant in "-DSAFETY -DNOREDUCE" "-DSAFETY"; do
        (cd "$WORK" && gcc -O2 $variant -DMEMLIM=16000 -o pan pan.c)
        read -r secs kib < <(measure "$WORK/pan" -c0 -m10000000)
        stored=$(awk '/states, stored/ {print $1; exit}' "$WORK/out")
        ptime=$(awk '/elapsed time/ {print $4; exit}' "$WORK/out")
        # SPIN's own figure for the states: stored * (state vector + overhead)
        mem=$(awk '/equivalent memory usage for states/ {print $1; exit}' "$WORK/out")
        label="spin ${variant/-DSAFETY /}"
        printf "%-10s %-16s %12s %9.2f %12.0f %9.1f %9.1f\n" "$name" "${label/-DSAFETY/default POR}" "$stored" "$ptime" \
            "$(python3 -c "print($stored/max($ptime,1e-9))")" "$(python3 -c "print($kib/1024)")" \
            "$(python3 -c "print($mem*1048576/max($stored,1))")"
    done
done
