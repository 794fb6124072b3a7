#!/usr/bin/env python3
"""Checks that the committed result tables still match what the code produces.

    python3 tests/docs/results_reproduce.py HBIRL_BINARY SOURCE_DIR [FOLDER ...]

docs/results/<folder>/*_runs.csv are the runs behind every figure and table of
docs/results.md. Nothing ties them to the code: once, the onion figure's CSV no
longer matched what `hbirl experiment onion` produced, and nobody noticed for about
100 commits. A full re-run takes hours, but every experiment seeds each run from its
own key (run and |E|, a task's seed and draw, a cell's m and q), not from its position
in the run or the number of runs, so a small subset of a run reproduces the full run's
rows bit for bit. This re-runs one small subset per folder (ENTRIES: the committed
run's own options, plus options that select a subset) into a temporary directory with
the given binary, and compares every produced row with the committed row of the same
key: every cell, as text, except the timing columns (IGNORED_COLUMNS).

It prints one line per mismatch (folder, row key, column: committed vs produced), one
line for a produced row whose key is not in the committed CSV, for a subset that
produces no rows and for a run that fails, and exits 1 if there is any; otherwise one
line per runs CSV and a total, and exits 0. A table marked `stale` is one known not to
reproduce today: its mismatches are printed as notes, not failures, until someone
re-runs it or drops the mark; a column marked `unrecorded` (added after some committed
rows were run) is compared only where the committed row has it. FOLDER arguments
restrict the check to those folders.
Standard library only, so that ctest can run it anywhere (tests/CMakeLists.txt,
docs.results_reproduce). About 25 s on one busy core (each subset on one thread, so that
ctest runs other tests beside it).
"""
import csv
import os
import subprocess
import sys
import tempfile
import time
from collections import namedtuple

# Wall-clock time of a run: the one thing that differs between two runs of the same code.
IGNORED_COLUMNS = {"seconds"}
# Each subset takes seconds; a run that hangs fails with its command named.
RUN_TIMEOUT_SECONDS = 120

# stale: why the whole table is known not to reproduce today (None: it must);
# unrecorded: {column: why} for columns added to the CSV after some committed rows were
# run: a committed cell of one that is empty is not compared (the rest must match).
Entry = namedtuple("Entry", "folder csv key args stale unrecorded")
Entry.__new__.__defaults__ = (None, {})

GRIDWORLD_KEY = ("run", "method", "confounders")
ONION_KEY = ("run", "method", "trajectories")
RANDOM_KEY = ("seed", "draw", "method")
CALIBRATION_KEY = ("seed", "draw", "demonstrations", "data")
STOPPING_KEY = ("seed", "draw", "demonstrations")

# The random tasks' `score` column (the held-out likelihood that chose the prior's
# strength) was added to the runs CSV in 0aa7efc, after most of these tables were run:
# their rows have it empty where the code now fills it (random_tasks_summary.md says so:
# "empty in the other methods' rows"). Every other column of those rows reproduces, and
# so does the score of the rows run since.
SCORE_NOT_RECORDED = {"score": "empty in rows run before it was recorded (0aa7efc)"}


def calibration(folder, *args):
    """A calibration folder's entry: its runs CSV, key, and `hbirl experiment calibration ARGS`."""
    return Entry(folder, "calibration_runs.csv", CALIBRATION_KEY, ["calibration", *args, "--threads", "1"])


def stopping(folder, *args):
    """A stopping folder's entry: one task of `hbirl experiment stopping ARGS`."""
    return Entry(folder, "stopping_runs.csv", STOPPING_KEY, ["stopping", *args, "--tasks", "1", "--threads", "1"])


def random_tasks(folder, csv_name, methods, *args, unrecorded=None):
    """A random-tasks runs CSV's entry: one task, one draw of --methods METHODS with ARGS
    (their --first-seed, when given, after the default's)."""
    return Entry(folder, csv_name, RANDOM_KEY,
                 ["random-tasks", "--tasks", "1", "--draws", "1", *args, "--methods", methods, "--threads", "1"],
                 unrecorded=unrecorded or {})

# One entry per checked runs CSV: the folder under docs/results, the file, the columns
# that identify a row and the `hbirl experiment` arguments of a subset of the command
# that made it (docs/results.md and each folder's *_summary.md give the commands; the
# options after the committed ones select the subset). Every subset was checked against
# wider ones (other runs, seeds, draws, cells; the whole Gridworld, unlisted and
# controlled-onion runs): a run's rows do not depend on which others run with it.
ENTRIES = [
    # hbirl experiment gridworld --runs 65
    Entry("gridworld", "gridworld_runs.csv", GRIDWORLD_KEY,
          ["gridworld", "--runs", "2", "--confounders", "0,3,15", "--threads", "1"]),
    # hbirl experiment gridworld --runs 65 --tie-actions
    Entry("gridworld_tied", "gridworld_runs.csv", GRIDWORLD_KEY,
          ["gridworld", "--runs", "2", "--confounders", "0,3", "--tie-actions", "--threads", "1"]),
    # hbirl experiment onion --runs 100
    Entry("onion", "onion_runs.csv", ONION_KEY,
          ["onion", "--runs", "2", "--trajectories", "1,2,10", "--threads", "1"]),
    # hbirl experiment onion --config controlled --runs 100
    Entry("onion_controlled", "onion_runs.csv", ONION_KEY,
          ["onion", "--config", "controlled", "--runs", "2", "--trajectories", "1,2", "--threads", "1"]),
    # hbirl experiment onion-regimes --runs 16 --shares 0,0.3,0.6,0.9 --eta-powers 1,3
    Entry("onion_regimes", "onion_regimes_runs.csv", ("foreground_share", "mirror", "eta_power", "run", "method"),
          ["onion-regimes", "--runs", "1", "--shares", "0.9", "--eta-powers", "1,3", "--threads", "1"]),
    # hbirl experiment eta-sensitivity (30 runs, |E| = 3, 7, every m and q)
    Entry("eta_sensitivity", "eta_sensitivity_runs.csv", ("run", "confounders", "mass", "accuracy", "method"),
          ["eta-sensitivity", "--runs", "2", "--confounders", "3", "--masses", "0.8", "--accuracies", "0.2,1.0",
           "--threads", "1"]),
    # hbirl experiment unlisted (30 runs, |E| = 0, 1, 3, 5, 7, told 0 and 1)
    Entry("unlisted", "unlisted_runs.csv", ("run", "confounders", "told", "method"),
          ["unlisted", "--runs", "2", "--confounders", "0,3", "--told", "0,1", "--threads", "1"]),
    # hbirl experiment random-tasks --tasks 200 --draws 3, in several runs of --methods
    # joined (random_tasks_summary.md).
    random_tasks("random_tasks", "random_tasks_runs.csv",
                 "true_trajectories,fixed_prior,paper_c0.5,posterior,posterior_from_truth,oracle_sensor,"
                 "posterior_end_sensor,oracle_sensor_labelled_o,posterior_tied",
                 unrecorded=SCORE_NOT_RECORDED),
    # hbirl experiment calibration (200 tasks from seed 5001, 3 draws, 200 samples)
    calibration("calibration", "--tasks", "1", "--draws", "1"),
    # hbirl experiment calibration --first-seed 7001 --samples 100 (BENCHMARKS.md)
    calibration("calibration_live_draws", "--first-seed", "7001", "--samples", "100", "--tasks", "1", "--draws", "1"),
    # hbirl experiment calibration --tasks-from gridworld --first-seed 1 --tasks 180
    calibration("calibration_gridworld", "--tasks-from", "gridworld", "--first-seed", "1", "--tasks", "2"),
    # hbirl experiment calibration --tasks-from gridworld --first-seed 1 --tasks 90 --demonstrations 2,4,8
    calibration("calibration_gridworld_prefixes", "--tasks-from", "gridworld", "--first-seed", "1", "--tasks", "1",
                "--demonstrations", "2,4,8"),
    # hbirl experiment calibration --tasks-from onion --first-seed 1 --tasks 100 --demonstrations 1,2,3
    calibration("calibration_onion", "--tasks-from", "onion", "--first-seed", "1", "--tasks", "1",
                "--demonstrations", "1,2,3"),
    # hbirl experiment stopping (60 tasks from seed 8001); task 8006 has 5 demonstrations
    stopping("stopping", "--first-seed", "8006"),
    # hbirl experiment stopping --tasks-from gridworld|onion --first-seed 1 --tasks 90|60
    stopping("stopping_gridworld", "--tasks-from", "gridworld", "--first-seed", "1"),
    stopping("stopping_onion", "--tasks-from", "onion", "--first-seed", "1"),
    # random_tasks' posterior and oracle rows and --tasks 200 --draws 3 --methods
    # oracle_subject_o,oracle_elements_o,oracle_seen_subject_o,posterior_s1,posterior_s1000
    random_tasks("random_tasks_split", "random_tasks_runs.csv", "oracle_subject_o,posterior_s1",
                 unrecorded=SCORE_NOT_RECORDED),
    # --tasks 200 --draws 3 --controlled N --methods posterior (1600: and posterior_s1)
    random_tasks("random_tasks_controlled", "controlled_100_runs.csv", "posterior", "--controlled", "100",
                 unrecorded=SCORE_NOT_RECORDED),
    random_tasks("random_tasks_controlled", "controlled_400_runs.csv", "posterior", "--controlled", "400",
                 unrecorded=SCORE_NOT_RECORDED),
    random_tasks("random_tasks_controlled", "controlled_1600_runs.csv", "posterior_s1", "--controlled", "1600",
                 unrecorded=SCORE_NOT_RECORDED),
    # --tasks 200 --draws 1 --demonstrations N, several runs of --methods joined
    random_tasks("random_tasks_demonstrations", "demonstrations_40_runs.csv", "posterior,oracle_sensor,posterior_s1",
                 "--demonstrations", "40"),
    random_tasks("random_tasks_demonstrations", "demonstrations_160_runs.csv", "oracle_sensor",
                 "--demonstrations", "160"),
    # --tasks 100 --first-seed 1001 --draws 3 --methods posterior,posterior_elements100,posterior_elements1000
    random_tasks("random_tasks_elements", "elements_runs.csv", "posterior_elements100", "--first-seed", "1001"),
    # random_tasks' posterior rows and --tasks 200 --draws 3 --methods posterior_elements1000
    random_tasks("random_tasks_elements", "benchmark_runs.csv", "posterior_elements1000"),
    # --tasks 100|100|800 --first-seed 1001|2001|3001 --draws 3, --methods posterior(,oracle_sensor)
    # and --methods posterior_tied, joined
    random_tasks("random_tasks_tied", "seeds1001_runs.csv", "posterior,oracle_sensor,posterior_tied",
                 "--first-seed", "1001"),
    random_tasks("random_tasks_tied", "seeds2001_runs.csv", "posterior,posterior_tied", "--first-seed", "2001"),
    random_tasks("random_tasks_tied", "seeds3001_runs.csv", "posterior,posterior_tied", "--first-seed", "3001"),
    # --tasks 100 --first-seed 1001 --draws 3: posterior,oracle_sensor (above) joined with
    # --methods oracle_sensor_labelled_others,posterior_from_truth
    random_tasks("random_tasks_heldout", "seeds1001_runs.csv",
                 "posterior,oracle_sensor,oracle_sensor_labelled_others,posterior_from_truth", "--first-seed", "1001"),
    # --tasks 200 --draws 3 --methods posterior_base0.3,posterior_base0.1
    random_tasks("random_tasks_base", "base_runs.csv", "posterior_base0.3"),
]


def read_csv(path):
    """The header and rows (lists of cells) of a CSV file."""
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        return [], []
    return rows[0], rows[1:]


def rows_by_key(header, rows, key):
    """{key tuple: {column: cell}}; raises ValueError on a missing key column."""
    missing = [k for k in key if k not in header]
    if missing:
        raise ValueError("no key column %s in %s" % (", ".join(missing), ",".join(header)))
    out = {}
    for row in rows:
        cells = dict(zip(header, row))
        out[tuple(cells.get(k, "") for k in key)] = cells
    return out


def describe_key(key, values):
    return " ".join("%s=%s" % kv for kv in zip(key, values))


def run_subset(binary, entry, out_dir):
    """Runs the entry's subset into out_dir; returns (produced CSV path, error or None)."""
    command = [binary, "experiment"] + entry.args + ["--out", out_dir]
    try:
        done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              universal_newlines=True, timeout=RUN_TIMEOUT_SECONDS)
    except subprocess.TimeoutExpired:
        return None, "%s took more than %d s" % (" ".join(command[1:]), RUN_TIMEOUT_SECONDS)
    if done.returncode != 0:
        tail = " | ".join(done.stderr.strip().splitlines()[-3:])
        return None, "%s exited %d: %s" % (" ".join(command[1:]), done.returncode, tail)
    produced = sorted(n for n in os.listdir(out_dir) if n.endswith("_runs.csv"))
    if len(produced) != 1:
        return None, "%s wrote %s, not one *_runs.csv" % (" ".join(command[1:]), produced or "nothing")
    return os.path.join(out_dir, produced[0]), None


def compare(entry, committed_path, produced_path):
    """(problems, notes, rows compared): one line per difference; a committed row's
    empty cell in the entry's unrecorded columns is not compared (a note says how many)."""
    c_header, c_rows = read_csv(committed_path)
    p_header, p_rows = read_csv(produced_path)
    where = "%s/%s" % (entry.folder, entry.csv)
    problems = []
    notes = []
    for column in p_header:
        if column not in c_header and column not in IGNORED_COLUMNS:
            problems.append("%s: column %s is produced but not in the committed CSV" % (where, column))
    for column in c_header:
        if column not in p_header and column not in IGNORED_COLUMNS:
            problems.append("%s: column %s is committed but no longer produced" % (where, column))
    try:
        committed = rows_by_key(c_header, c_rows, entry.key)
        produced = rows_by_key(p_header, p_rows, entry.key)
    except ValueError as e:
        return problems + ["%s: %s" % (where, e)], notes, 0
    if not produced:
        problems.append("%s: `hbirl experiment %s` produced no rows" % (where, " ".join(entry.args)))
    columns = [c for c in p_header if c in c_header and c not in IGNORED_COLUMNS and c not in entry.key]
    unrecorded_rows = 0
    for key, row in produced.items():
        old = committed.get(key)
        if old is None:
            problems.append("%s: %s: produced, but not in the committed CSV" % (where, describe_key(entry.key, key)))
            continue
        differing = [c for c in columns if old.get(c, "") != row.get(c, "")]
        unrecorded = [c for c in differing if c in entry.unrecorded and not old.get(c, "")]
        if unrecorded:
            unrecorded_rows += 1
            differing = [c for c in differing if c not in unrecorded]
        if differing:
            problems.append("%s: %s: %s" % (where, describe_key(entry.key, key), "; ".join(
                "%s: committed %s vs produced %s" % (c, old.get(c, "") or "''", row.get(c, "") or "''")
                for c in differing)))
    if unrecorded_rows:
        notes.append("%s: %d of %d committed rows lack a column the code now fills, not compared there (%s)" % (
            where, unrecorded_rows, len(produced),
            "; ".join("%s: %s" % (c, why) for c, why in sorted(entry.unrecorded.items()))))
    return problems, notes, len(produced)


def check(binary, root, entry, scratch):
    """(failures, notes, rows compared, seconds) for one entry."""
    committed_path = os.path.join(root, "docs", "results", entry.folder, entry.csv)
    if not os.path.isfile(committed_path):
        return ["%s/%s: missing" % (entry.folder, entry.csv)], [], 0, 0.0
    out_dir = os.path.join(scratch, entry.folder + "_" + entry.csv)
    start = time.time()
    produced_path, error = run_subset(binary, entry, out_dir)
    if error:
        return ["%s: %s" % (entry.folder, error)], [], 0, time.time() - start
    problems, notes, rows = compare(entry, committed_path, produced_path)
    seconds = time.time() - start
    if entry.stale:
        if problems:
            notes += ["known stale (%s), not a failure: %s" % (entry.stale, p) for p in problems]
        else:
            notes.append("%s/%s is marked stale (%s) but now reproduces: drop the mark"
                         % (entry.folder, entry.csv, entry.stale))
        problems = []
    return problems, notes, rows, seconds


def main(argv):
    if len(argv) < 3:
        print("usage: results_reproduce.py HBIRL_BINARY SOURCE_DIR [FOLDER ...]", file=sys.stderr)
        return 2
    binary = os.path.abspath(argv[1])
    root = os.path.abspath(argv[2])
    only = set(argv[3:])
    entries = [e for e in ENTRIES if not only or e.folder in only]
    unknown = only - {e.folder for e in ENTRIES}
    if unknown:
        print("no entry for %s" % ", ".join(sorted(unknown)), file=sys.stderr)
        return 2
    start = time.time()
    failures = []
    total_rows = 0
    with tempfile.TemporaryDirectory(prefix="results_reproduce.") as scratch:
        for entry in entries:
            problems, notes, rows, seconds = check(binary, root, entry, scratch)
            for line in notes + problems:
                print(line)
            failures += problems
            total_rows += rows
            if not problems:
                print("%s/%s: %d rows of `hbirl experiment %s` %s (%.1f s)"
                      % (entry.folder, entry.csv, rows, " ".join(entry.args),
                         "match but for the notes above" if notes else "reproduce", seconds))
    if failures:
        print("%d problems: a committed table above is older than the code (re-run it as docs/results.md "
              "and its summary say) or the code changed what it produces" % len(failures))
        return 1
    print("%d rows of %d runs CSVs reproduce the committed docs/results tables (%.0f s)"
          % (total_rows, len(entries), time.time() - start))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
