#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Robustness benchmark: how methods degrade under injected faults (docs/faults.md).

Public logs (default): for each log (intel, aces, fr079) x each fault at two severities (the
FAULTS table below) x each method (map --method hector|graph|rbpf, odometry --matcher pl-icp,
localize --method mcl from the known first pose or with --global, in the map of the building's
corrected log: LOCALIZATION below):
    slam2d perturb LOG --out LOG2 --fault SPEC --seed SEED --quiet --json
    slam2d map LOG2 --method METHOD --out DIR --quiet --json      (or: slam2d odometry LOG2 --matcher pl-icp ...)
    slam2d eval TRAJ --relations RELATIONS --json
and the same method on the clean log; prints a markdown table of the mean translational relation
error (m) of the perturbed run and its ratio to the clean run (or, with --json, one JSON document).
Beside each method, the column 'odometry (m)' is the same error of the perturbed log's odometry
alone (`slam2d map LOG2 --method odometry`: its odometry poses as the trajectory), the error a
method starts from. The last column is the relations scored in the perturbed / the clean run:
decimate, scan-rate and scan-gap remove scans, so some relations have no pose; then the clean
error is the clean run's over the same relations (its poses at the scans the perturbed run kept),
so the ratio compares like with like. Every run is also scored on the relations at most 10 s apart
(SHORT_SPAN); --harm prints the do-no-harm table of issue 40 from both scores: per log and
condition (the clean log included) the odometry's and each method's error at 10 s / over all,
bold where the method is above the odometry at 10 s, + where over all it exceeds 1.5x its clean
error. Faults that move stamps (jitter, backwards) are scored at
the original stamps: the method sees the moved ones, then its trajectory's scan i gets
the original scan i's stamp back before `slam2d eval`.

Corrected logs (--corrected): the eight SLAM-corrected logs of $SLAM2D_DATA/carmen-corrected,
whose FLASER poses are the reference trajectory. Each is first reduced to its PARAM and FLASER
lines (its ODOM lines are the raw odometry in another frame, its NEFF lines filter diagnostics;
no method reads either), so the laser lines' odometry is the corrected trajectory itself. That
odometry is degraded with the injector (DEGRADE below: wheel-scale + heading-drift + stall), the
methods run on the degraded log, and
    slam2d eval TRAJ --reference REF --json
gives ATE and RPE against REF, the corrected poses written as 'stamp x y theta'. The row
'odometry' is the degraded odometry itself. With --faults given, each fault at each severity is
injected into the degraded log as well (`perturb DEGRADED --fault SPEC`), and every run is scored
with `--rpe-window time --rpe-delta 10`: the do-no-harm table of issue 40, where a method's RPE
over 10 s windows is set against the odometry's on the same log, and its ATE against its own ATE
on the degraded log without the fault. Logs whose FLASER stamps are not strictly increasing
(belgioioso: printed with 6 significant digits, so all equal; freiburg-campus and orebro: all 0)
get the scan index as the stamp, in both the reduced log and REF; there, the fault windows count
scans, not seconds ('every=60' is every 60 scans).

Usage: bench/datasets/robustness_benchmark.py [--slam2d build/release/bin/slam2d] [--data $SLAM2D_DATA]
           [--logs intel aces fr079] [--faults stall decimate ...] [--severities mild severe]
           [--methods hector graph rbpf pl-icp] [--seed 1] [--jobs 1] [--quick] [--corrected]
           [--out /tmp/slam2d_robustness_benchmark] [--resume] [--json] [--harm]
--quick: aces only, the severe severity, faults stall, wheel-scale, decimate, range-max and
spurious-short, methods hector and pl-icp (with --corrected: edmonton and seattle); an explicit
--logs/--faults/--severities/--methods wins over the --quick choice. --resume reuses the results
already in --out. The full public run is 3 logs x 22 faults x 2 severities x 6 methods (the MCL
rows on intel and fr079 only) and one odometry run per log, fault and severity: hours on 2 cores.
"""

import argparse
import concurrent.futures
import gzip
import json
import os
import sys

from common import run_json, fmt

LOGS = {
    "intel": ("intel/intel.clf.gz", "intel/intel.relations"),
    "aces": ("aces/aces.clf.gz", "aces/aces.relations"),
    "fr079": ("fr079/fr079.clf.gz", "fr079/fr079.relations"),
}
CORRECTED_LOGS = ["acapulco", "belgioioso", "edmonton", "fhw", "freiburg-101", "freiburg-campus", "orebro", "seattle"]

# fault -> (mild, severe) specs.
FAULTS = {
    "stall": ("stall:every=60,duration=1.2", "stall:every=60,duration=3"),
    "odom-gap": ("odom-gap:every=60,duration=1.2", "odom-gap:every=60,duration=3"),
    "odom-reset": ("odom-reset:every=120", "odom-reset:every=30"),
    "wheel-scale": ("wheel-scale:translation=1.02", "wheel-scale:translation=1.05,rotation=1.02"),
    "heading-drift": ("heading-drift:rate=0.5", "heading-drift:rate=2"),
    "odom-shift": ("odom-shift:by=0.3", "odom-shift:by=0.6"),          # the odometry runs ahead
    "odom-shift-lag": ("odom-shift:by=-0.3", "odom-shift:by=-0.6"),    # the odometry lags
    "scan-gap": ("scan-gap:every=60,duration=1.2", "scan-gap:every=60,duration=3"),
    "decimate": ("decimate:k=2", "decimate:k=4"),
    "scan-rate": ("scan-rate:hz=2", "scan-rate:hz=1"),
    "jitter": ("jitter:sigma=0.01", "jitter:sigma=0.05"),
    "duplicate": ("duplicate:p=0.01", "duplicate:p=0.05"),
    "backwards": ("backwards:p=0.01,by=0.5", "backwards:p=0.05,by=0.5"),
    "range-noise": ("range-noise:sigma=0.03", "range-noise:sigma=0.1"),
    "spurious-max": ("spurious-max:p=0.01", "spurious-max:p=0.05"),
    "spurious-short": ("spurious-short:p=0.01", "spurious-short:p=0.05"),
    "spurious-far": ("spurious-far:p=0.02", "spurious-far:p=0.1"),
    "mixed-pixels": ("mixed-pixels:p=0.5", "mixed-pixels:p=1,alternate=6"),
    "glass": ("glass:sectors=1,width=30", "glass:sectors=3,width=45"),
    "laser-noise": ("laser-noise:sigma=0.03,bearing=0.25", "laser-noise:sigma=0.1,bearing=1"),
    "beams": ("beams:k=2", "beams:k=4"),
    "fov": ("fov:deg=120", "fov:deg=90"),
    "range-max": ("range-max:max=30", "range-max:max=5.6"),
}
SEVERITIES = ["mild", "severe"]
# Faults that move scan stamps: the trajectory is scored at the original stamps (scan i to scan i),
# since the relations name the true ones.
RESTAMP = {"jitter", "backwards"}
# The odometry degradation of the corrected logs, applied in this order.
DEGRADE = ["wheel-scale:translation=1.03,rotation=1.01", "heading-drift:rate=0.5", "stall:every=60,duration=1.2"]
METHODS = ["hector", "graph", "rbpf", "pl-icp", "mcl", "mcl-global"]
# Localization (mcl: tracking from the known first pose; mcl-global: --global, scored after
# converged_at_s) runs in a map built from the SLAM-corrected log of the same building with
# `slam2d map CORRECTED --method odometry` (its odometry triples are the corrected poses). The raw
# log's first scan in that map (docs/methods/localization.md); ACES has none known, so no MCL row.
LOCALIZATION = {
    "intel": {"corrected": "intel/intel-corrected.log.gz", "initial": "-0.0718,-0.1626,0.2200", "extra": []},
    "fr079": {"corrected": "fr079/freiburg-079-corrected.log.gz", "initial": "0.0012,-0.0011,0.0", "extra": []},
}
QUICK = {"logs": ["aces"], "corrected_logs": ["edmonton", "seattle"], "severities": ["severe"],
         "faults": ["stall", "wheel-scale", "decimate", "range-max", "spurious-short"], "methods": ["hector", "pl-icp"]}


def method_command(args, method, log, out_dir, localization=None):
    """The command that runs `method` on `log`, and the trajectory it writes. Localization methods
    need `localization`: {"map": MAP.yaml, "initial": "x,y,theta", "extra": [...]}."""
    if method in ("mcl", "mcl-global"):
        if localization is None:
            raise RuntimeError(f"{method}: no map of this building with a known first pose")
        trajectory = os.path.join(out_dir, "trajectory.txt")
        start = ["--global"] if method == "mcl-global" else ["--initial", localization["initial"]]
        return [args.slam2d, "localize", log, "--map", localization["map"], "--method", "mcl", *start,
                *localization["extra"], "--seed", str(args.seed), "--out", trajectory, "--quiet", "--json"], trajectory
    if method == "pl-icp":
        trajectory = os.path.join(out_dir, "trajectory.txt")
        return [args.slam2d, "odometry", log, "--matcher", "pl-icp", "--out", trajectory, "--quiet", "--json"], trajectory
    command = [args.slam2d, "map", log, "--method", method, "--out", out_dir, "--quiet", "--json"]
    return command, os.path.join(out_dir, "trajectory.txt")


def laser_stamps(log_path):
    """The ipc stamps of the FLASER lines of a (possibly gzipped) log, as text, in file order."""
    opener = gzip.open if log_path.endswith(".gz") else open
    with opener(log_path, "rt") as f:
        return [tokens[int(tokens[1]) + 8] for tokens in (line.split() for line in f) if tokens and tokens[0] == "FLASER"]


def restore_stamps(trajectory, original_log, perturbed_log, out):
    """Rewrites the trajectory's stamps from the perturbed log's scan stamps to the original ones
    (scan i to scan i), so that a fault that moves stamps is scored on the same relations."""
    original, perturbed = laser_stamps(original_log), laser_stamps(perturbed_log)
    if len(original) != len(perturbed):
        raise RuntimeError(f"{perturbed_log}: {len(perturbed)} scans for {len(original)} in {original_log}")
    to_original = {float(p): o for p, o in zip(perturbed, original)}
    with open(trajectory) as f, open(out, "w") as restored:
        for line in f:
            tokens = line.split()
            if tokens and not tokens[0].startswith("#") and float(tokens[0]) in to_original:
                tokens[0] = to_original[float(tokens[0])]
            restored.write(" ".join(tokens) + "\n")
    return out


def after_convergence(trajectory, converged_at_s, out):
    """The trajectory without the poses before converged_at_s (s after its first stamp)."""
    with open(trajectory) as f:
        lines = [line for line in f if line.strip() and not line.startswith("#")]
    first = float(lines[0].split()[0])
    with open(out, "w") as kept:
        kept.writelines(line for line in lines if float(line.split()[0]) >= first + converged_at_s)
    return out


def run_method(args, method, log, out_dir, eval_arguments, original_log=None, localization=None, short_span=None):
    """Runs the method and the evaluation; keeps the result in out_dir/result.json (for --resume).
    With original_log, the trajectory's stamps are first mapped back to that log's (restore_stamps).
    A global localization is scored after it converged (converged_at_s is kept in the result).
    With short_span (s), the relations at most that far apart are scored as well (error_short)."""
    result_path = os.path.join(out_dir, "result.json")
    if args.resume and os.path.exists(result_path):
        with open(result_path) as f:
            return json.load(f)
    os.makedirs(out_dir, exist_ok=True)
    command = []
    try:
        command, trajectory = method_command(args, method, log, out_dir, localization)
        summary = run_json(command)
        if original_log:
            trajectory = restore_stamps(trajectory, original_log, log, os.path.join(out_dir, "trajectory_original_stamps.txt"))
        converged_at_s = summary.get("converged_at_s")
        if method == "mcl-global":
            if converged_at_s is None:
                raise RuntimeError("never converged")
            trajectory = after_convergence(trajectory, converged_at_s, os.path.join(out_dir, "trajectory_converged.txt"))
        error = run_json([args.slam2d, "eval", trajectory, *eval_arguments, "--json"])
        result = {"error": error, "cpu_s": summary.get("cpu_s"), "converged_at_s": converged_at_s,
                  "warnings": summary.get("warnings"), "command": " ".join(command)}
        if short_span is not None:
            result["error_short"] = run_json([args.slam2d, "eval", trajectory, *eval_arguments, "--max-span",
                                              str(short_span), "--json"])
    except (RuntimeError, json.JSONDecodeError) as failure:
        result = {"error": None, "failure": str(failure), "command": " ".join(command)}
    with open(result_path, "w") as f:
        json.dump(result, f)
    return result


def perturb(args, log, specs, out):
    if not (args.resume and os.path.exists(out)):
        command = [args.slam2d, "perturb", log, "--out", out, "--seed", str(args.seed), "--quiet", "--json"]
        for spec in specs:
            command += ["--fault", spec]
        return run_json(command)
    return None


def parallel(args, function, items):
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        return list(pool.map(lambda item: function(*item), items))


def ratio(value, clean):
    return value / clean if value is not None and clean else None


# ---------------------------------------------------------------------------------------------
# Public logs against their relations.

# The do-no-harm rule of issue 40 on the public logs: a method given odometry is no worse than that
# odometry alone on the relations at most SHORT_SPAN s apart, and within HARM_RATIO times its clean
# error over all relations.
SHORT_SPAN = 10.0
HARM_RATIO = 1.5

def public_benchmark(args):
    logs_dir = os.path.join(args.out, "logs")
    os.makedirs(logs_dir, exist_ok=True)
    cases = [(log, fault, severity) for log in args.logs for fault in args.faults for severity in args.severities]

    def perturbed_path(log, fault, severity):
        return os.path.join(logs_dir, f"{log}_{fault}_{severity}.clf.gz")

    spec_of = {(fault, severity): FAULTS[fault][SEVERITIES.index(severity)] for fault in args.faults for severity in args.severities}
    perturb_summaries = parallel(args, lambda log, fault, severity: perturb(
        args, os.path.join(args.data, LOGS[log][0]), [spec_of[fault, severity]], perturbed_path(log, fault, severity)), cases)

    localization = {}
    if any(method.startswith("mcl") for method in args.methods):
        for log in args.logs:
            if log in LOCALIZATION:
                entry = LOCALIZATION[log]
                map_dir = os.path.join(args.out, "maps", log)
                if not (args.resume and os.path.exists(os.path.join(map_dir, "map.yaml"))):
                    run_json([args.slam2d, "map", os.path.join(args.data, entry["corrected"]), "--method", "odometry",
                              "--out", map_dir, "--quiet", "--json"])
                localization[log] = {"map": os.path.join(map_dir, "map.yaml"), "initial": entry["initial"],
                                     "extra": entry["extra"]}

    def run(log, fault, severity, method):
        relations = ["--relations", os.path.join(args.data, LOGS[log][1])]
        original = os.path.join(args.data, LOGS[log][0])
        source = original if fault == "clean" else perturbed_path(log, fault, severity)
        out_dir = os.path.join(args.out, "runs", f"{method}_{log}_{fault}_{severity}")
        return run_method(args, method, source, out_dir, relations, original if fault in RESTAMP else None,
                          localization.get(log), SHORT_SPAN)

    def run_dir(log, fault, severity, method):
        return os.path.join(args.out, "runs", f"{method}_{log}_{fault}_{severity}")

    runs = [(log, "clean", "-", method) for log in args.logs for method in args.methods + ["odometry"]]
    runs += [(log, fault, severity, method) for (log, fault, severity) in cases for method in args.methods + ["odometry"]]
    results = dict(zip(runs, parallel(args, run, runs)))
    rows = []
    for (log, fault, severity, method), result in results.items():
        if method == "odometry":
            continue
        odometry_run = results.get((log, fault, severity, "odometry"), {})
        odometry, odometry_short = odometry_run.get("error"), odometry_run.get("error_short")
        clean = results[log, "clean", "-", method]["error"]
        clean_short = results[log, "clean", "-", method].get("error_short")
        if clean and result["error"] and result["error"]["relations"] != clean["relations"]:
            same_scans = (args, run_dir(log, "clean", "-", method), run_dir(log, fault, severity, method),
                          os.path.join(args.data, LOGS[log][1]))
            clean = clean_on_same_scans(*same_scans)
            clean_short = clean_on_same_scans(*same_scans, ["--max-span", str(SHORT_SPAN)]) if clean_short else None
        value = result["error"]["trans_mean"] if result["error"] else None
        short = result.get("error_short")
        clean_value = clean["trans_mean"] if clean else None
        rows.append({"log": log, "fault": fault, "severity": severity,
                     "spec": spec_of.get((fault, severity), ""), "method": method,
                     "trans_mean_m": value, "clean_trans_mean_m": clean_value, "ratio": ratio(value, clean_value),
                     "odometry_trans_mean_m": odometry["trans_mean"] if odometry else None,
                     "short_trans_mean_m": short["trans_mean"] if short else None,
                     "clean_short_trans_mean_m": clean_short["trans_mean"] if clean_short else None,
                     "odometry_short_trans_mean_m": odometry_short["trans_mean"] if odometry_short else None,
                     "rot_mean_deg": result["error"]["rot_mean_deg"] if result["error"] else None,
                     "relations": result["error"]["relations"] if result["error"] else None,
                     "clean_relations": clean["relations"] if clean else None,
                     "cpu_s": result.get("cpu_s"), "converged_at_s": result.get("converged_at_s"),
                     "failure": result.get("failure"), "command": result["command"]})
    changes = {f"{log}/{fault}/{severity}": summary for (log, fault, severity), summary in zip(cases, perturb_summaries) if summary}
    return rows, changes


def clean_on_same_scans(args, clean_dir, perturbed_dir, relations, eval_options=()):
    """The clean run's relation error over the scans the perturbed run kept (decimate, scan-gap),
    so that both are scored on the same relations (eval_options: e.g. --max-span S)."""
    kept = set()
    for name in ("trajectory_original_stamps.txt", "trajectory.txt"):
        path = os.path.join(perturbed_dir, name)
        if os.path.exists(path):
            with open(path) as f:
                kept = {float(line.split()[0]) for line in f if line.strip() and not line.startswith("#")}
            break
    subset = os.path.join(perturbed_dir, "clean_same_scans.txt")
    with open(os.path.join(clean_dir, "trajectory.txt")) as f, open(subset, "w") as out:
        out.writelines(line for line in f if line.strip() and not line.startswith("#") and float(line.split()[0]) in kept)
    return run_json([args.slam2d, "eval", subset, "--relations", relations, *eval_options, "--json"])


def print_public_table(rows):
    print("| log | fault | severity | spec | method | clean (m) | perturbed (m) | ratio | odometry (m) | relations |")
    print("|---|---|---|---|---|---:|---:|---:|---:|---:|")
    for r in rows:
        if r["fault"] == "clean":
            continue
        print(f"| {r['log']} | {r['fault']} | {r['severity']} | `{r['spec']}` | {r['method']} | {fmt(r['clean_trans_mean_m'])}"
              f" | {fmt(r['trans_mean_m']) if r['trans_mean_m'] is not None else 'failed'} | {fmt(r['ratio'], 2)}"
              f" | {fmt(r['odometry_trans_mean_m'])} | {r['relations']}/{r['clean_relations']} |")


def print_public_harm_table(rows, methods):
    """The do-no-harm table of issue 40 on the public logs: per log and condition, the odometry's
    and each method's error on the relations at most SHORT_SPAN s apart / over all relations (m);
    bold where the method is above the odometry at SHORT_SPAN s, + where its error over all
    relations exceeds HARM_RATIO times its clean one (on the same scans)."""
    print(f"error on relations at most {SHORT_SPAN:g} s apart / over all relations (m); **bold**: above the odometry"
          f" at {SHORT_SPAN:g} s; +: over all relations more than {HARM_RATIO:g}x the method's clean error")
    print()
    print("| log | condition | odometry | " + " | ".join(methods) + " |")
    print("|---|---|---|" + "---|" * len(methods))
    by_key = {(r["log"], r["fault"], r["severity"], r["method"]): r for r in rows}
    harmed = unstable = cells = 0
    conditions = [("clean", "-")] + list(dict.fromkeys((r["fault"], r["severity"]) for r in rows if r["fault"] != "clean"))
    for log in dict.fromkeys(r["log"] for r in rows):
        for fault, severity in conditions:
            first = next((by_key[log, fault, severity, m] for m in methods if (log, fault, severity, m) in by_key), None)
            if first is None:
                continue
            odometry_short, odometry_all = first["odometry_short_trans_mean_m"], first["odometry_trans_mean_m"]
            condition = "clean" if fault == "clean" else f"`{first['spec']}`"
            cells_text = []
            for method in methods:
                r = by_key.get((log, fault, severity, method))
                if r is None or r["trans_mean_m"] is None:
                    cells_text.append("failed" if r else "-")
                    continue
                short, value = r["short_trans_mean_m"], r["trans_mean_m"]
                worse = short is not None and odometry_short is not None and short > odometry_short
                blown = r["ratio"] is not None and r["ratio"] > HARM_RATIO
                harmed, unstable, cells = harmed + worse, unstable + blown, cells + 1
                short_text = f"**{fmt(short, 4)}**" if worse else fmt(short, 4)
                cells_text.append(f"{short_text} / {fmt(value)}{' +' if blown else ''}")
            print(f"| {log} | {condition} | {fmt(odometry_short, 4)} / {fmt(odometry_all)} | " + " | ".join(cells_text) + " |")
    print()
    print(f"cells above the odometry at {SHORT_SPAN:g} s: {harmed} of {cells}; over all relations beyond"
          f" {HARM_RATIO:g}x clean: {unstable}")


# ---------------------------------------------------------------------------------------------
# Corrected logs against their own poses.

def reduce_corrected_log(source, log_out, reference_out):
    """Keeps the PARAM and FLASER lines; writes REF 'stamp x y theta' from the FLASER odometry
    triple. Stamps stay when strictly increasing, else become the scan index (in both files)."""
    params, flasers = [], []
    with gzip.open(source, "rt") as f:
        for line in f:
            tokens = line.split()
            if tokens and tokens[0] == "PARAM":
                params.append(line.rstrip("\n"))
            elif tokens and tokens[0] == "FLASER":
                flasers.append(tokens)
    stamps = [float(t[int(t[1]) + 8]) for t in flasers]
    use_index = any(b <= a for a, b in zip(stamps, stamps[1:]))
    with open(log_out, "w") as log, open(reference_out, "w") as reference:
        log.write("# PARAM and FLASER lines of %s%s\n" % (os.path.basename(source), ", scan index as stamp" if use_index else ""))
        for line in params:
            log.write(line + "\n")
        for index, tokens in enumerate(flasers):
            n = int(tokens[1])
            stamp = str(index) if use_index else tokens[n + 8]
            body = tokens[:n + 8]
            log.write(" ".join(body + [stamp, "nohost", stamp]) + "\n")
            reference.write(f"{stamp} {tokens[n + 5]} {tokens[n + 6]} {tokens[n + 7]}\n")
    return use_index


def odometry_trajectory(log_path, out):
    """'stamp x y theta' of the FLASER odometry triples of a (possibly gzipped) log."""
    opener = gzip.open if log_path.endswith(".gz") else open
    with opener(log_path, "rt") as f, open(out, "w") as trajectory:
        for line in f:
            tokens = line.split()
            if tokens and tokens[0] == "FLASER":
                n = int(tokens[1])
                trajectory.write(f"{tokens[n + 8]} {tokens[n + 5]} {tokens[n + 6]} {tokens[n + 7]}\n")


def corrected_benchmark(args, faults):
    """faults: [] for the degradation alone, else the (fault, severity) pairs injected on top of it."""
    work = os.path.join(args.out, "corrected")
    os.makedirs(work, exist_ok=True)
    index_stamps = {}
    for name in args.logs:
        source = os.path.join(args.data, "carmen-corrected", f"{name}-corrected.log.gz")
        index_stamps[name] = reduce_corrected_log(source, os.path.join(work, f"{name}.clf"), os.path.join(work, f"{name}.ref.txt"))
    parallel(args, lambda name: perturb(args, os.path.join(work, f"{name}.clf"), DEGRADE,
                                        os.path.join(work, f"{name}_degraded.clf")), [(name,) for name in args.logs])
    # Localization: the map of the clean reduced log (its poses are the reference), the first pose known.
    localization = {}
    if any(method.startswith("mcl") for method in args.methods):
        for name in args.logs:
            map_dir = os.path.join(work, f"{name}_map")
            if not (args.resume and os.path.exists(os.path.join(map_dir, "map.yaml"))):
                run_json([args.slam2d, "map", os.path.join(work, f"{name}.clf"), "--method", "odometry", "--out", map_dir,
                          "--quiet", "--json"])
            with open(os.path.join(work, f"{name}.ref.txt")) as f:
                first = f.readline().split()
            localization[name] = {"map": os.path.join(map_dir, "map.yaml"), "initial": ",".join(first[1:4]), "extra": []}

    conditions = ["clean", "degraded"] + [f"{fault}-{severity}" for fault, severity in faults]
    spec_of = {f"{fault}-{severity}": FAULTS[fault][SEVERITIES.index(severity)] for fault, severity in faults}
    def inject(name, condition):
        """None, or why the fault does not apply to this log (e.g. far returns beyond a 10 m scanner's range)."""
        try:
            perturb(args, os.path.join(work, f"{name}_degraded.clf"), [spec_of[condition]], os.path.join(work, f"{name}_{condition}.clf"))
            return None
        except RuntimeError as failure:
            return str(failure).split(": ", 1)[-1].strip()

    cases = [(name, condition) for name in args.logs for condition in spec_of]
    inapplicable = {case: reason for case, reason in zip(cases, parallel(args, inject, cases)) if reason}
    # Scored on 10 s windows where faults are asked for (the do-no-harm table), else on 1 m of travel.
    rpe = ["--rpe-window", "time", "--rpe-delta", "10"] if faults else []

    def run(name, condition, method):
        if (name, condition) in inapplicable:
            return {"error": None, "failure": "not applicable: " + inapplicable[name, condition], "command": ""}
        log = os.path.join(work, f"{name}.clf" if condition == "clean" else f"{name}_{condition}.clf")
        reference = ["--reference", os.path.join(work, f"{name}.ref.txt"), *rpe]
        out_dir = os.path.join(args.out, "runs", f"corrected_{method}_{name}_{condition}" + ("_rpe10s" if faults else ""))
        if method == "odometry":
            os.makedirs(out_dir, exist_ok=True)
            trajectory = os.path.join(out_dir, "trajectory.txt")
            odometry_trajectory(log, trajectory)
            return {"error": run_json([args.slam2d, "eval", trajectory, *reference, "--json"]), "command": "(input odometry)"}
        return run_method(args, method, log, out_dir, reference, localization=localization.get(name))

    runs = [(name, condition, method) for name in args.logs for condition in conditions
            for method in ["odometry"] + args.methods]
    rows = []
    for (name, condition, method), result in zip(runs, parallel(args, run, runs)):
        error = result["error"] or {}
        rows.append({"log": name, "condition": condition, "spec": spec_of.get(condition, ""), "method": method,
                     "index_stamps": index_stamps[name],
                     "ate_rmse_m": error.get("ate_rmse"), "rpe_trans_rmse_m": error.get("rpe_trans_rmse"),
                     "rpe_trans_mean_m": error.get("rpe_trans_mean"), "rpe_delta_s": error.get("rpe_delta_s"),
                     "rpe_rot_rmse_deg": error.get("rpe_rot_rmse_deg"), "matched": error.get("matched"),
                     "converged_at_s": result.get("converged_at_s"),
                     "failure": result.get("failure"), "command": result["command"]})
    return rows


def print_corrected_table(rows):
    print(f"degradation: {' then '.join(DEGRADE)}")
    print()
    print("| log | method | clean ATE (m) | degraded ATE (m) | degraded RPE (m) | degraded RPE (deg) |")
    print("|---|---|---:|---:|---:|---:|")
    by_key = {(r["log"], r["condition"], r["method"]): r for r in rows}
    for r in rows:
        if r["condition"] != "degraded":
            continue
        clean = by_key[r["log"], "clean", r["method"]]
        name = r["log"] + (" (index stamps)" if r["index_stamps"] else "")
        print(f"| {name} | {r['method']} | {fmt(clean['ate_rmse_m'])} | {fmt(r['ate_rmse_m'])}"
              f" | {fmt(r['rpe_trans_rmse_m'])} | {fmt(r['rpe_rot_rmse_deg'], 2)} |")


def print_harm_table(rows, methods):
    """Per log and condition: the odometry's and each method's RPE over 10 s windows / ATE (m);
    bold where the method's RPE is above the odometry's; the ATE's ratio to the method's on the
    degraded log without the fault."""
    print(f"degradation: {' then '.join(DEGRADE)}, then the condition's fault; RPE over 10 s windows (10 scans"
          " where the stamps are the index) / ATE (m); in brackets ATE / ATE without the fault")
    print()
    print("| log | condition | odometry | " + " | ".join(methods) + " |")
    print("|---|---|---|" + "---|" * len(methods))
    by_key = {(r["log"], r["condition"], r["method"]): r for r in rows}
    harmed = cells = 0
    for r in rows:
        if r["method"] != "odometry" or r["condition"] == "clean":
            continue
        odometry = r["rpe_trans_mean_m"]
        name = r["log"] + (" (index stamps)" if r["index_stamps"] else "")
        condition = f"`{r['spec']}`" if r["spec"] else r["condition"]
        if (r["failure"] or "").startswith("not applicable"):
            print(f"| {name} | {condition} | {r['failure']} |" + " |" * len(methods))
            continue
        cells_text = []
        for method in methods:
            m = by_key[r["log"], r["condition"], method]
            base = by_key[r["log"], "degraded", method]["ate_rmse_m"]
            if m["rpe_trans_mean_m"] is None:
                cells_text.append("failed")
                continue
            worse = odometry is not None and m["rpe_trans_mean_m"] > odometry
            harmed, cells = harmed + worse, cells + 1
            rpe_text = f"**{fmt(m['rpe_trans_mean_m'], 4)}**" if worse else fmt(m["rpe_trans_mean_m"], 4)
            cells_text.append(f"{rpe_text} / {fmt(m['ate_rmse_m'])} ({fmt(ratio(m['ate_rmse_m'], base), 2)})")
        print(f"| {name} | {condition} | {fmt(odometry, 4)} / {fmt(r['ate_rmse_m'])} | " + " | ".join(cells_text) + " |")
    print()
    print(f"cells worse than the odometry over 10 s: {harmed} of {cells}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--slam2d", default=os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d"))
    parser.add_argument("--data", default=os.environ.get("SLAM2D_DATA", "/work/shared/data"))
    parser.add_argument("--logs", nargs="+")
    parser.add_argument("--faults", nargs="+", choices=list(FAULTS))
    parser.add_argument("--severities", nargs="+", choices=SEVERITIES)
    parser.add_argument("--methods", nargs="+", choices=METHODS)
    parser.add_argument("--seed", type=int, default=1, help="seed of slam2d perturb")
    parser.add_argument("--jobs", type=int, default=1, help="runs at a time")
    parser.add_argument("--quick", action="store_true", help="a small subset (see above)")
    parser.add_argument("--corrected", action="store_true", help="the corrected logs, ATE/RPE against their poses")
    parser.add_argument("--out", default="/tmp/slam2d_robustness_benchmark")
    parser.add_argument("--resume", action="store_true", help="reuse results already in --out")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--harm", action="store_true",
                        help="public logs: print the do-no-harm table (10 s / all, against the odometry) instead")
    args = parser.parse_args()

    known_logs = CORRECTED_LOGS if args.corrected else list(LOGS)
    quick_logs = QUICK["corrected_logs"] if args.corrected else QUICK["logs"]
    args.logs = args.logs or (quick_logs if args.quick else known_logs)
    unknown = [log for log in args.logs if log not in known_logs]
    if unknown:
        parser.error(f"unknown logs {unknown}; choose from {known_logs}")
    faults_given = args.faults is not None
    args.faults = args.faults or (QUICK["faults"] if args.quick else list(FAULTS))
    args.severities = args.severities or (QUICK["severities"] if args.quick else SEVERITIES)
    args.methods = args.methods or (QUICK["methods"] if args.quick else METHODS)

    if args.corrected:
        faults = [(fault, severity) for fault in args.faults for severity in args.severities] if faults_given else []
        rows = corrected_benchmark(args, faults)
        if args.json:
            json.dump({"degrade": DEGRADE, "seed": args.seed, "results": rows}, sys.stdout, indent=2)
            print()
        elif faults:
            print_harm_table(rows, args.methods)
        else:
            print_corrected_table(rows)
        return
    rows, changes = public_benchmark(args)
    if args.json:
        json.dump({"seed": args.seed, "results": rows, "perturb": changes}, sys.stdout, indent=2)
        print()
    elif args.harm:
        print_public_harm_table(rows, args.methods)
    else:
        print_public_table(rows)
    for r in rows:
        if r["failure"]:
            print(f"failed: {r['log']} {r['fault']} {r['severity']} {r['method']}: {r['failure']}", file=sys.stderr)


if __name__ == "__main__":
    main()
