# SPDX-License-Identifier: BSD-3-Clause
"""Sweeps of (log x method x config) on Dask distributed: one task each.

    python3 -m slam2d.sweep --logs LOG... --methods graph,rbpf [--configs GRID.yaml]
                            [--relations-dir DIR] --out DIR [--workers N | --scheduler ADDRESS]

Each task runs `slam2d map` in its own process (a crash or an exhausted machine loses that task's
attempt, never the worker pool or the other tasks) into OUT/runs/LOG__METHOD__CONFIG/ (map,
trajectory, summary.json), evaluates the trajectory against LOG's relations when there are some,
and writes result.json there last, atomically. A task with a result.json is done: rerunning the
sweep skips it. A failed task is retried (--retries), then reported with its error; the others go
on. OUT/results.csv and OUT/results.md hold one row per task: log, method, config, status,
trans_mean (m), rot_mean_deg, cpu_s, peak_rss_mb, out.

GRID.yaml names configurations per method, each a dict of the method's fields
(slam2d.default_config(METHOD)); without it each method runs with its defaults ("default"):

    graph:
      coarse: {map_resolution: 0.1}
      fine: {map_resolution: 0.025}
    rbpf:
      default: {}

Relations: DIR/NAME.relations for a log named NAME.clf.gz, NAME.bag, ... (--relations-dir), else
a NAME.relations beside the log, else none (error columns empty).
"""

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

import yaml

COLUMNS = ["log", "method", "config", "status", "trans_mean", "rot_mean_deg", "cpu_s", "peak_rss_mb", "out"]


def log_name(path):
    """intel.clf.gz -> intel, aces.orig.bag -> aces.orig, a rosbag2 folder -> its name."""
    name = os.path.basename(os.path.normpath(path))
    for suffix in (".gz", ".clf", ".log", ".bag", ".mcap"):
        if name.endswith(suffix):
            name = name[: -len(suffix)]
    return name


def find_relations(log, relations_dir):
    name = log_name(log)
    candidates = [os.path.join(relations_dir, f"{name}.relations")] if relations_dir else []
    candidates.append(os.path.join(os.path.dirname(os.path.normpath(log)), f"{name}.relations"))
    return next((c for c in candidates if os.path.isfile(c)), None)


def make_tasks(logs, methods, grid, relations_dir, out):
    tasks = []
    for log in logs:
        for method in methods:
            for config_name, fields in (grid.get(method) or {"default": {}}).items():
                folder = os.path.join(out, "runs", f"{log_name(log)}__{method}__{config_name}")
                tasks.append({"log": os.path.abspath(log), "method": method, "config": config_name,
                              "fields": fields or {}, "relations": find_relations(log, relations_dir), "out": folder})
    return tasks


def run_task(task, slam2d):
    """One map run in a child process, its evaluation, and result.json written last."""
    os.makedirs(task["out"], exist_ok=True)
    command = [slam2d, "map", task["log"], "--method", task["method"], "--out", os.path.join(task["out"], "map"),
               "--quiet", "--json"]
    if task["fields"]:
        preset = os.path.join(task["out"], "config.yaml")
        with open(preset, "w", encoding="utf-8") as f:
            json.dump({"method": task["method"], **task["fields"]}, f)
        command += ["--config", preset]
    mapped = subprocess.run(command, capture_output=True, text=True)
    if mapped.returncode != 0:
        raise RuntimeError(mapped.stderr.strip() or f"slam2d map exited with {mapped.returncode}")
    summary = json.loads(mapped.stdout)
    row = {"log": log_name(task["log"]), "method": task["method"], "config": task["config"], "status": "ok",
           "trans_mean": None, "rot_mean_deg": None, "cpu_s": summary["cpu_s"],
           "peak_rss_mb": summary["peak_rss_mb"], "out": task["out"]}
    if task["relations"]:
        evaluated = subprocess.run([slam2d, "eval", os.path.join(task["out"], "map", "trajectory.txt"), "--relations",
                                    task["relations"], "--json"], capture_output=True, text=True, check=True)
        error = json.loads(evaluated.stdout)
        row["trans_mean"], row["rot_mean_deg"] = error["trans_mean"], error["rot_mean_deg"]
    with tempfile.NamedTemporaryFile("w", dir=task["out"], delete=False, suffix=".tmp") as f:
        json.dump(row, f)
    os.replace(f.name, os.path.join(task["out"], "result.json"))
    return row


def done_row(task):
    path = os.path.join(task["out"], "result.json")
    if not os.path.isfile(path):
        return None
    with open(path, encoding="utf-8") as f:
        return json.load(f)


def run_sweep(client, tasks, slam2d, retries=2, on_result=None):
    """Runs the tasks not done yet on `client` (a dask.distributed Client); returns one row per task,
    in task order. `on_result(row)` is called as each finishes (progress, tests)."""
    from distributed import as_completed

    rows = [done_row(task) for task in tasks]
    pending = {}
    for index, task in enumerate(tasks):
        if rows[index] is None:
            future = client.submit(run_task, task, slam2d, retries=retries, pure=False,
                                   key=f"slam2d-{os.path.basename(task['out'])}")
            pending[future] = index
    for future in as_completed(list(pending)):
        index = pending[future]
        task = tasks[index]
        try:
            rows[index] = future.result()
        except Exception as error:  # the task failed every attempt: reported, the others go on
            rows[index] = {"log": log_name(task["log"]), "method": task["method"], "config": task["config"],
                           "status": f"failed: {error}".replace("\n", " ")[:500], "trans_mean": None,
                           "rot_mean_deg": None, "cpu_s": None, "peak_rss_mb": None, "out": task["out"]}
        if on_result:
            on_result(rows[index])
    return rows


def write_tables(rows, out):
    os.makedirs(out, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=out, delete=False, newline="", suffix=".tmp") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    os.replace(f.name, os.path.join(out, "results.csv"))

    def cell(value):
        return "" if value is None else f"{value:.4f}" if isinstance(value, float) else str(value)
    lines = ["| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(cell(row[c]) for c in COLUMNS) + " |" for row in rows]
    with tempfile.NamedTemporaryFile("w", dir=out, delete=False, suffix=".tmp") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(f.name, os.path.join(out, "results.md"))


def find_slam2d(given):
    found = given or os.environ.get("SLAM2D_BIN") or shutil.which("slam2d")
    if not found or not os.access(found, os.X_OK):
        sys.exit("slam2d.sweep: the slam2d tool was not found (give --slam2d PATH or set SLAM2D_BIN)")
    return os.path.abspath(found)


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python3 -m slam2d.sweep", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--logs", nargs="+", required=True)
    parser.add_argument("--methods", required=True, help="comma-separated: odometry, hector, graph, rbpf")
    parser.add_argument("--configs", help="GRID.yaml: named configurations per method")
    parser.add_argument("--relations-dir")
    parser.add_argument("--out", required=True)
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster workers (one thread each)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler instead of a LocalCluster")
    parser.add_argument("--retries", type=int, default=2)
    parser.add_argument("--slam2d", help="the slam2d tool (default: $SLAM2D_BIN, else slam2d on PATH)")
    parser.add_argument("--quiet", action="store_true")
    args = parser.parse_args(argv)

    from distributed import Client, LocalCluster

    grid = {}
    if args.configs:
        with open(args.configs, encoding="utf-8") as f:
            grid = yaml.safe_load(f) or {}
    tasks = make_tasks(args.logs, [m.strip() for m in args.methods.split(",") if m.strip()], grid,
                       args.relations_dir, args.out)
    slam2d = find_slam2d(args.slam2d)
    cluster = None if args.scheduler else LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                                                       dashboard_address=None)
    with Client(args.scheduler or cluster) as client:
        done = 0

        def progress(row):
            nonlocal done
            done += 1
            if not args.quiet:
                print(f"[{done}] {row['log']} {row['method']} {row['config']}: {row['status']}", file=sys.stderr)
        rows = run_sweep(client, tasks, slam2d, args.retries, progress)
    if cluster:
        cluster.close()
    write_tables(rows, args.out)
    failed = sum(row["status"] != "ok" for row in rows)
    print(f"{len(rows)} tasks, {failed} failed: {os.path.join(args.out, 'results.csv')}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
