# SPDX-License-Identifier: BSD-3-Clause
"""What the benchmark scripts of bench/datasets share: running slam2d, reading its trajectories,
writing results atomically, formatting table cells. Each script is run as
`/usr/bin/python3 bench/datasets/NAME.py`, so this folder is on its import path."""

import json
import os
import subprocess
import tempfile


class CommandFailed(RuntimeError):
    """A command that exited non-zero; the message holds the command and the end of its stderr."""


def failed(command, exit_code, stderr):
    """The CommandFailed of a command: its words, its exit code and the end of its stderr."""
    return CommandFailed(f"{' '.join(command)} failed (exit {exit_code}): {stderr.strip()[-2000:]}")


def run(command, nice=False):
    """The command's stdout; CommandFailed when it exits non-zero."""
    result = subprocess.run((["nice"] if nice else []) + command, capture_output=True, text=True)
    if result.returncode != 0:
        raise failed(command, result.returncode, result.stderr)
    return result.stdout


def run_measured(command):
    """(stdout, peak MB) of a command: it is reaped by wait4, which gives its own maximum RSS (the
    figure of /usr/bin/time -f %M); CommandFailed when it exits non-zero."""
    with tempfile.TemporaryFile() as err:
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=err)
        out = child.stdout.read()
        child.stdout.close()
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
        if child.returncode != 0:
            err.seek(0)
            raise failed(command, child.returncode, err.read().decode(errors="replace"))
    return out.decode(), usage.ru_maxrss / 1024.0


def run_json(command, nice=False):
    """The command's stdout parsed as JSON (slam2d ... --json)."""
    return json.loads(run(command, nice))


def write_report(slam2d, run_dirs, out, relations=None, log=None):
    """slam2d report over the run folders (docs/report.md): the page's path."""
    command = [slam2d, "report", *run_dirs, "--out", out, "--json"]
    command += ["--relations", relations] if relations else []
    command += ["--log", log] if log else []
    return run_json(command)["path"]


def read_trajectory(path):
    """A slam2d text trajectory as (t, x, y, theta) tuples; ValueError naming the line otherwise."""
    rows = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            if len(fields) != 4:
                raise ValueError(f"{path}:{number}: expected 't x y theta'")
            rows.append(tuple(float(v) for v in fields))
    return rows


def write_atomic(path, text):
    """Writes text to path through a temporary file beside it: a killed run leaves no half file."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".tmp-")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def fmt(value, digits=3):
    """A table cell: '-' for a missing value."""
    return "-" if value is None else f"{value:.{digits}f}"
