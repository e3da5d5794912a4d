"""Ctrl-C on `mdm-montecarlo`: it stops, says so in one line and keeps the rows that finished.

The command runs as a real process in its own process group and gets SIGINT as a terminal
would send it (to the whole group, workers included).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

from mdm_montecarlo.study.cases import study_rows

EXE = [sys.executable, "-m", "mdm_montecarlo.commands.cli"]
_DONE = re.compile(rb"\| *(\d+)/\d+ \[")


def _sigint_as_from_a_terminal() -> None:
    """SIGINT at its default in the command: a shell without job control starts background
    commands (``cmd &`` in a script) with SIGINT ignored, and the command would inherit that
    and never see the Ctrl-C this test sends."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupt_after(argv: list[str], runs_done: int) -> tuple[int, str, float]:
    """Start the command, wait until its progress bar shows ``runs_done`` runs finished, send
    SIGINT to its group; returns (exit status, stderr, seconds from SIGINT to exit)."""
    proc = subprocess.Popen(
        [*EXE, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
        preexec_fn=_sigint_as_from_a_terminal,  # noqa: PLW1509 - one signal call in the child
    )  # fmt: skip
    assert proc.stderr is not None
    seen = b""
    try:
        while True:
            chunk = os.read(proc.stderr.fileno(), 4096)
            assert chunk, f"exited before {runs_done} runs: {seen.decode()[-500:]}"
            seen += chunk
            counts = [int(m) for m in _DONE.findall(seen)]
            if counts and max(counts) >= runs_done:
                break
        sent = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)
        _, rest = proc.communicate(timeout=60)
        took = time.monotonic() - sent
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, (seen + rest).decode(), took


def _messages(stderr: str) -> list[str]:
    """stderr without the progress bar's redraws."""
    parts = re.split(r"[\r\n]", stderr)
    return [p for p in parts if p.strip() and not re.match(r"^[\w-]+:\s+\d+%\|", p)]


def test_ctrl_c_on_reproduce_keeps_the_finished_rows_in_a_marked_partial_report(
    tmp_path: Path,
) -> None:
    out = tmp_path / "report"
    argv = ["reproduce", "--tables", "simtable1", "--runs", "1000", "--workers", "2"]
    status, stderr, took = _interrupt_after([*argv, "--out", str(out)], runs_done=2000)
    print(f"stopped {took:.2f} s after SIGINT")
    assert status == 130
    (line,) = _messages(stderr)
    configurations = len({row.case for row in study_rows(("simtable1",))})
    assert line.startswith("mdm-montecarlo: interrupted; ")
    assert f"of {configurations} configurations finished, partial report:" in line
    assert took < 10  # a loose bound: a computing pool would run on for a minute
    report = (out / "report.md").read_text()
    assert "PARTIAL REPORT: interrupted" in report
    finished = int(re.search(r"interrupted; (\d+) of", line).group(1))  # type: ignore[union-attr]
    assert 2 <= finished < configurations
    rows = (out / "results.csv").read_text().splitlines()[1:]
    assert len(rows) == finished
    runs = (out / "samples-runs.csv").read_text().splitlines()[1:]
    assert len(runs) == finished * 1000
    assert (out / "samples-runs.parquet").is_file()
    assert (out / "provenance.json").is_file()


def test_ctrl_c_on_a_long_run_prints_one_line_and_the_partial_row() -> None:
    argv = ["run", "--profile", "paper-fixed", "--method", "US", "--runs", "400000"]
    status, stderr, took = _interrupt_after(argv, runs_done=1000)
    print(f"stopped {took:.2f} s after SIGINT")
    assert status == 130
    (line,) = _messages(stderr)
    assert re.fullmatch(
        r"mdm-montecarlo: interrupted: PARTIAL row from the \d+000 of 400000 runs that finished",
        line,
    )
    assert took < 10
