#!/usr/bin/env bash
# Every row of docs/performance.md's table, measured now on this machine, printed as one table.
#
#     tools/perf_table.sh            # about 5-6 minutes on the idle 2-core machine
#     PY=/path/to/python tools/perf_table.sh
#     QUICK=1 tools/perf_table.sh    # every command once with tiny counts: checks the script, not the machine
#
# Rows: the one-off pick (wall, CPU, peak RSS: median of 5), `--help` and `tree validate` (median of 5), the
# warm pick against its floor and the tick loop's own overhead (`bench budget`), what `--log` adds to the warm
# tick loop (tools/bench_log_overhead.py, interleaved), `bench eval --seeds 50` on 2 workers with each process's
# peak memory (tools/peak_memory.py), the second and third `run --resident`, and the log writers compared
# (tools/bench_mcap_writers.py). Commands run from the repository's root; the load average is printed with
# each row. Python's bytecode caches go to a temporary folder (PYTHONPYCACHEPREFIX) and are written by a first
# untimed run, as an installed bt_grasp has them: with PYTHONDONTWRITEBYTECODE=1 every command would compile
# bt_grasp's ~90 modules again (~0.08-0.1 s each time).
set -euo pipefail
cd "$(dirname "$0")/.."
PY=${PY:-.venv/bin/python}
WORK=$(mktemp -d /tmp/bt_grasp_perf.XXXXXX)
trap 'BT_GRASP_RESIDENT_DIR="$WORK/resident" "$PY" -m bt_grasp.cli.main resident stop >/dev/null 2>&1 || true; rm -rf "$WORK"' EXIT
unset PYTHONDONTWRITEBYTECODE
export PYTHONPYCACHEPREFIX="$WORK/pyc"
export BT_GRASP_RESIDENT_DIR="$WORK/resident"  # a resident process of this script's own
BT=("$PY" -m bt_grasp.cli.main)
RUN=(run trees/pick.xml --scene scenes/tabletop.yaml --quiet)
started=$(date +%s)
N=5; PAIRS=6; SEEDS=50; WREPS=3
if [[ "${QUICK:-0}" == 1 ]]; then N=1; PAIRS=1; SEEDS=1; WREPS=1; fi

load() { cut -d' ' -f1-3 /proc/loadavg; }
say() { echo "[$(( $(date +%s) - started )) s] $*" >&2; }

timed() {  # timed NAME REPS COMMAND...: appends "wall user sys maxrss_kib" lines to $WORK/NAME.time
    local name=$1 reps=$2; shift 2
    for _ in $(seq "$reps"); do
        /usr/bin/time -f "%e %U %S %M" -a -o "$WORK/$name.time" "$@" >/dev/null 2>>"$WORK/$name.err"
    done
    echo "$(load)" >"$WORK/$name.load"
}

say "warming bytecode caches and disk caches (not timed)"
"${BT[@]}" --help >/dev/null
"${BT[@]}" tree validate trees/pick.xml >/dev/null
"${BT[@]}" "${RUN[@]}" >/dev/null || true

say "one-off run x$N"; timed run "$N" "${BT[@]}" "${RUN[@]}"
say "--help x$N"; timed help "$N" "${BT[@]}" --help
say "tree validate x$N"; timed validate "$N" "${BT[@]}" tree validate trees/pick.xml

say "peak memory of one one-off run with --log (and the writer process)"
"$PY" tools/peak_memory.py --json -- "${BT[@]}" "${RUN[@]}" --log "$WORK/run.mcap" >/dev/null 2>"$WORK/run_memory.json"

say "bench budget --no-log (warm pick, floor, tick loop overhead)"
"${BT[@]}" bench budget --no-log --json >"$WORK/budget.json"; echo "$(load)" >"$WORK/budget.load"

say "--log overhead in the warm tick loop ($PAIRS interleaved pairs)"
"$PY" tools/bench_log_overhead.py --reps "$PAIRS" --configs=--log --out "$WORK/log_overhead.json" >/dev/null

say "run --resident: first (starts it), second, third"
timed resident_first 1 "${BT[@]}" "${RUN[@]}" --resident
timed resident 2 "${BT[@]}" "${RUN[@]}" --resident

say "log writers on the same messages (the --log run above)"
"$PY" tools/bench_mcap_writers.py "$WORK/run.mcap" --reps "$WREPS" --json >"$WORK/writers.json"

say "bench eval --seeds $SEEDS --workers 2, with each process's peak memory"
"$PY" tools/peak_memory.py --json -- "${BT[@]}" bench eval --seeds "$SEEDS" --workers 2 --json \
    >"$WORK/eval.json" 2>"$WORK/eval_memory.json"

say "done; the table:"
"$PY" - "$WORK" "$(( $(date +%s) - started ))" "$N" "$PAIRS" "$SEEDS" <<'EOF'
import json, statistics, sys
from pathlib import Path

work, elapsed, n, pairs, seeds = Path(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]

def times(name):
    rows = [list(map(float, line.split())) for line in (work / f"{name}.time").read_text().splitlines()
            if line and line[0].isdigit()]
    return rows

def med(rows, i):
    return statistics.median(r[i] for r in rows)

def load(name):
    return (work / f"{name}.load").read_text().strip()

def memory(path):
    text = [line for line in path.read_text().splitlines() if line.startswith("{")]
    return json.loads(text[-1])["roles"]

table = []
run = times("run")
table.append((f"one-off `bt-grasp run trees/pick.xml --scene scenes/tabletop.yaml --quiet`, wall, median of {n}",
              f"{med(run, 0):.2f} s", "<= 2.5 s", load("run")))
table.append((f"the same, CPU (user + sys), median of {n}", f"{statistics.median(r[1] + r[2] for r in run):.2f} s",
              "<= 4 s", load("run")))
table.append((f"the same, peak RSS, median of {n}", f"{med(run, 3) / 1024:.0f} MiB", "<= 450 MiB", load("run")))
mem = memory(work / "run_memory.json")
table.append(("one run with --log: the log writer process's peak RSS", f"{mem.get('log writer', {}).get('peak_mib', '-')} MiB",
              "", ""))
table.append((f"`bt-grasp --help`, wall, median of {n}", f"{med(times('help'), 0):.2f} s", "<= 0.3 s", load("help")))
table.append((f"`bt-grasp tree validate trees/pick.xml`, wall, median of {n}", f"{med(times('validate'), 0):.2f} s",
              "<= 0.3 s", load("validate")))
budget = json.loads((work / "budget.json").read_text())
floor = budget["floor"]["floor_s"]
table.append(("warm pick (bench budget --no-log): tick loop / floor",
              f"{budget['tick_loop_wall_s'] / floor:.2f}x ({budget['tick_loop_wall_s']:.3f} / {floor:.3f} s)",
              "<= 1.25x", load("budget")))
over = json.loads((work / "log_overhead.json").read_text())
cfg = over["configs"]
table.append((f"`--log` overhead in the warm tick loop ({pairs} interleaved pairs, ratio of medians)",
              f"{cfg['--log']['overhead_pct']:+.1f}% ({cfg['no log']['wall_s_median']:.3f} -> "
              f"{cfg['--log']['wall_s_median']:.3f} s)", "<= 5%", " ".join(f"{x:.2f}" for x in over["load_average"])))
resident = times("resident")
table.append(("second and third `run --resident`, wall", " / ".join(f"{r[0]:.2f} s" for r in resident), "<= 0.8 s",
              load("resident")))
ev = json.loads((work / "eval.json").read_text())
w2 = ev["runs"]["eval run --workers 2"]
table.append((f"`bench eval --seeds {seeds}`, 2 workers", f"{w2['episodes_per_min']:.1f} episodes/min "
              f"({w2['successes']}/{w2['episodes']} ok)", ">= 160", " ".join(f"{x:.2f}" for x in ev["load_after"])))
emem = memory(work / "eval_memory.json")
table.append(("a campaign worker's peak RSS (bench eval)", f"{emem.get('campaign worker', {}).get('peak_mib', '-')} MiB",
              "", ""))
wr = json.loads((work / "writers.json").read_text())
for name, r in wr["writers"].items():
    table.append((f"log writer `{name}`: tick loop / helpers per tick ({wr['ticks']} ticks)",
                  f"{r['caller_us_per_tick']:.1f} / {r['helper_us_per_tick']:.1f} us", "",
                  " ".join(f"{x:.2f}" for x in wr["load_average"])))

width = max(len(r[0]) for r in table)
print(f"{'row':{width}s} | {'now':28s} | {'goal':10s} | load (1/5/15 min)")
print("-" * (width + 60))
for what, now, goal, ld in table:
    print(f"{what:{width}s} | {now:28s} | {goal:10s} | {ld}")
print(f"\n(total {elapsed} s; {Path('/proc/cpuinfo').read_text().count('processor')} CPUs)")
EOF
