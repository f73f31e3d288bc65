# SPDX-License-Identifier: BSD-3-Clause
"""Every --json output is valid JSON in valid UTF-8 (issue 25): a log whose skipped lines carry
binary junk in their type names, and a file name that is not UTF-8, still give a summary that a
strict parser reads, the junk written as U+FFFD; and a file that is not a log is refused by name."""

import json
import os
import subprocess

CLI = os.environ.get("SLAM2D_BIN", "build/release/bin/slam2d")
FLASER = b"FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.5 host 1.5\n"


def run(*arguments):
    return subprocess.run([CLI, *arguments], capture_output=True)


def test_info_json_is_strict_utf8_with_junk_in_skipped_lines(tmp_path):
    log = tmp_path / "junk-types.clf"
    log.write_bytes(FLASER + b"\xff\xfe\x80TYPE 1 2\n" + b"CAF\xc3\xa9 1\n" + b"\xed\xa0\x80 1\n" + FLASER)
    result = run("info", str(log), "--json")
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout.decode("utf-8"))  # strict: invalid UTF-8 raises
    types = summary["skipped_types"]
    assert types["\ufffd\ufffd\ufffdTYPE"] == 1
    assert types["CAF\u00e9"] == 1  # well-formed UTF-8 is kept as it is
    assert types["\ufffd\ufffd\ufffd"] == 1  # an encoded surrogate is not well-formed
    assert summary["scans"] == 2


def test_a_file_name_that_is_not_utf8_gives_valid_json(tmp_path):
    name = os.path.join(os.fsencode(tmp_path), b"log-\xff.clf")
    with open(name, "wb") as f:
        f.write(FLASER)
    result = subprocess.run([os.fsencode(CLI), b"info", name, b"--json"], capture_output=True)
    assert result.returncode == 0, result.stderr
    summary = json.loads(result.stdout.decode("utf-8"))
    assert summary["file"].endswith("log-\ufffd.clf")


def test_a_binary_is_refused_by_name(tmp_path):
    binary = tmp_path / "random.bin"
    binary.write_bytes(bytes((i * 7919 + 13) % 256 for i in range(4096)))
    result = run("info", str(binary), "--json")
    assert result.returncode != 0
    assert b"random.bin:1: not a CARMEN log" in result.stderr
    assert result.stdout == b""
