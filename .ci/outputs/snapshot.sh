#!/usr/bin/env bash
# snapshot.sh REPO OUT: the deterministic outputs of checkout REPO into the folder OUT.
set -u
repo=$(cd "$1" && pwd); mkdir -p "$2"; out=$(cd "$2" && pwd)
cd "$repo"
export PYTHONPATH=$repo
z() { python3 -m zrp "$@"; }
z ik > "$out/ik.txt" 2>&1
z paper --out "$out/paper" --no-video > "$out/paper.txt" 2>&1
z measure --model puma --out "$out/m1.csv" --effect backlash:2=0.002 --seed 3 > "$out/measure1.txt" 2>&1
z measure --model puma --out "$out/m2.csv" --effect link_length:3=0.5,0,0mm --seed 4 --deg \
    > "$out/measure2.txt" 2>&1
z diagnose --model puma --data "$out/m1.csv" --out "$out/d1" --seed 0 --no-plots --no-progress \
    > "$out/d1.txt" 2>&1
z diagnose --model puma --data "$out/m2.csv" --deg --out "$out/d2" --seed 1 --no-plots \
    --no-progress > "$out/d2.txt" 2>&1
z calibrate --model puma --data "$out/m1.csv" --out "$out/c1" --seed 0 > "$out/c1.txt" 2>&1
z gap-benchmark --scenarios 4 --seed 2 --poses 100 --out "$out/gb" --workdir "$out/gbw" \
    --no-plots --no-progress > "$out/gb.txt" 2>&1
z motion-benchmark --scenarios 3 --seed 1 --moves 4 --out "$out/mb" --no-progress > "$out/mb.txt" 2>&1
z study > "$out/study.txt" 2>&1
z lessons --out "$out/lessons" > "$out/lessons.txt" 2>&1 || true
