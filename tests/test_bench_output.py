"""Every bench's `--json` lines and PNG come from bench/_output.py: keys carry their unit, and
numbers stay numbers, so that a script can read any bench's results the same way."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[1] / "bench"
sys.path.insert(0, str(BENCH))

from _output import as_number, json_key, json_rows, plot_tables  # noqa: E402

PNG = b"\x89PNG\r\n\x1a\n"


def test_a_header_becomes_a_snake_case_key_ending_in_its_unit() -> None:
    assert json_key("p50 (ms)") == "p50_ms"
    assert json_key("p99 ms") == "p99_ms"
    assert json_key("put µs") == "put_us"
    assert json_key("RSS at 10 s (MB)") == "rss_at_10_s_mb"
    assert json_key("triples/CPU-s") == "triples_per_cpu_s"
    assert json_key("1 txn each: cs/s") == "1_txn_each_cs_per_s"


def test_cells_that_read_as_numbers_are_numbers_and_others_stay_text() -> None:
    assert as_number("1,234") == 1234
    assert as_number("0.25") == 0.25
    assert as_number(2.123456789) == 2.123
    assert as_number(float("nan")) is None
    assert as_number(None) is None
    assert as_number("0.5..0.9") == "0.5..0.9"
    assert as_number(True) == "True"


def test_each_row_is_one_json_object_named_by_its_first_cell() -> None:
    lines = json_rows(
        "latency",
        ["case", "p50 (ms)", "p99 ms", "p99 ms", "min..max"],
        [["project", 2.5, 9.0, 8.0, "1.0..12.0"], ["firing", "7", 20, 19, "-"]],
    )
    first, second = map(json.loads, lines)
    assert first == {
        "case": "project",
        "p50_ms": 2.5,
        "p99_ms": 9.0,
        "p99_ms_2": 8.0,
        "min_max": "1.0..12.0",
        "table": "latency",
    }
    assert second["case"] == "firing" and second["p50_ms"] == 7


def test_the_numeric_columns_are_drawn_and_a_table_without_any_draws_nothing(
    tmp_path: Path,
) -> None:
    path = tmp_path / "out" / "tables.png"
    tables = [
        ("one", ["case", "p50 (ms)", "note"], [["a", 1.0, "x"], ["b", 2.0, "y"]]),
        ("two", ["measure", "median (ms)"], [["hop", 0.4]]),
    ]
    assert plot_tables(tables, path)
    assert path.read_bytes().startswith(PNG)
    assert not plot_tables([("text", ["case", "note"], [["a", "x"]])], tmp_path / "none.png")
    assert not (tmp_path / "none.png").exists()


def test_a_bench_prints_json_lines_and_writes_its_png(tmp_path: Path) -> None:
    png = tmp_path / "keys.png"
    done = subprocess.run(
        [sys.executable, str(BENCH / "advanced_keys.py"), "--keys", "20", "--json", "--plot", png],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    )
    rows = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert [r["case"] for r in rows] == [
        "session.put (the store now)",
        "AdvancedPublisher per key",
    ]
    assert all(isinstance(r["declare_ms"], float | int) and r["put_us"] > 0 for r in rows)
    assert f"plot: {png}" in done.stdout
    assert png.read_bytes().startswith(PNG)


def test_no_plot_writes_no_png(tmp_path: Path) -> None:
    png = tmp_path / "keys.png"
    subprocess.run(
        [
            sys.executable,
            str(BENCH / "advanced_keys.py"),
            "--keys",
            "5",
            "--no-plot",
            "--plot",
            png,
        ],
        capture_output=True,
        timeout=120,
        check=True,
    )
    assert not png.exists()
