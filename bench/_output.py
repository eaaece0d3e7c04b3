"""What every bench prints: aligned tables, with `--json` one JSON object per row, and a PNG.

One place for it, so that every bench answers the same flags the same way: `bench_parser()` is
the argparse parser with `--json`, `--plot PATH` and `--no-plot`; `parse()` reads them, and
from then on `print_table` prints each row as JSON too and redraws the tables' numeric
columns into the PNG. A bench that draws (or prints JSON) of its own says so to `parse()`,
and `print_table` leaves that part to it.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

OUT = Path(__file__).parent / "out"


@dataclass
class _Settings:
    json: bool = False
    plot: Path | None = None  # where print_table draws the tables so far; None: nowhere
    tables: list[tuple[str, list[str], list[list[object]]]] = field(default_factory=list)
    announced: bool = False


_settings = _Settings()


def bench_parser(doc: str | None) -> argparse.ArgumentParser:
    """Return an argparse parser (described by `doc`'s first line) with the shared flags."""
    parser = argparse.ArgumentParser(description=(doc or "").splitlines()[0] if doc else None)
    parser.add_argument(
        "--json", action="store_true", help="also one JSON object per line per case"
    )
    parser.add_argument(
        "--plot", type=Path, metavar="PNG", help="where the PNG goes (default: bench/out/)"
    )
    parser.add_argument("--no-plot", action="store_true", help="write no PNG")
    return parser


def parse(
    parser: argparse.ArgumentParser,
    argv: Sequence[str] | None = None,
    *,
    own_json: bool = False,
    own_plot: bool = False,
) -> argparse.Namespace:
    """Parse the options and set `print_table` up by them.

    `own_json`, `own_plot`: the bench prints its JSON lines, or draws its PNG (at `png()`),
    itself; `print_table` does not.
    """
    args = parser.parse_args(argv)
    _settings.json = args.json and not own_json
    _settings.plot = None if own_plot else png(args, f"{Path(sys.argv[0]).stem}.png")
    return args


def png(args: argparse.Namespace, name: str) -> Path | None:
    """Return where the PNG goes: `--plot`, else bench/out/`name`; None with `--no-plot`."""
    return None if args.no_plot else args.plot or OUT / name


def json_key(header: str) -> str:
    """Return a header as a snake_case key, its unit a suffix: "p50 (ms)" -> "p50_ms"."""
    text = header.replace("µ", "u").replace("%", " pct")
    text = re.sub(r"\s*/\s*", " per ", text)
    return re.sub(r"[^0-9a-z]+", "_", text.lower()).strip("_")


def as_number(cell: object) -> object:
    """Return a cell as a number if it reads as one ("1,234" -> 1234; NaN, "": None), else as is."""
    if cell is None or cell == "":
        return None
    if isinstance(cell, str):
        try:
            number = float(cell.replace(",", ""))
        except ValueError:
            return cell
        cell = int(number) if number.is_integer() else number
    if isinstance(cell, bool) or not isinstance(cell, int | float):
        return str(cell)
    if isinstance(cell, float):
        return float(f"{cell:.4g}") if math.isfinite(cell) else None
    return cell


def json_rows(title: str, header: Sequence[str], rows: Sequence[Sequence[object]]) -> list[str]:
    """Return one JSON object per row: `case` (the first cell), then a key per other column."""
    keys: list[str] = []
    seen: Counter[str] = Counter()
    for key in map(json_key, header[1:]):  # a key twice would lose a column: number the later
        seen[key] += 1
        keys.append(key if seen[key] == 1 else f"{key}_{seen[key]}")
    lines = []
    for row in rows:
        line: dict[str, object] = {"case": str(row[0])}
        line |= dict(zip(keys, map(as_number, row[1:]), strict=True))
        line["table"] = title
        lines.append(json.dumps(line, allow_nan=False, default=str))
    return lines


def _numeric_columns(header: Sequence[str], rows: Sequence[Sequence[object]]) -> list[int]:
    numbers = [[as_number(r[i]) for r in rows] for i in range(len(header))]
    return [
        i
        for i in range(1, len(header))
        if all(isinstance(v, int | float) and not isinstance(v, bool) for v in numbers[i])
    ]


def plot_tables(
    tables: Sequence[tuple[str, Sequence[str], Sequence[Sequence[object]]]], path: Path
) -> bool:
    """Draw each table's numeric columns, a bar per case, into the PNG `path`.

    Returns False (and draws nothing) when no table has a numeric column.
    """
    panels = [
        (n, header[i], [str(r[0]) for r in rows], [float(as_number(r[i])) for r in rows])  # type: ignore[arg-type]
        for n, (_, header, rows) in enumerate(tables)
        for i in _numeric_columns(header, rows)
    ]
    if not panels:
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = min(3, len(panels))
    lines = math.ceil(len(panels) / columns)
    tall = max(len(cases) for _, _, cases, _ in panels) * 0.3 + 1.2
    figure, axes = plt.subplots(
        lines, columns, figsize=(6 * columns, tall * lines), squeeze=False, layout="constrained"
    )
    for axis, (n, name, cases, values) in zip(axes.flat, panels, strict=False):
        axis.barh(range(len(values)), values)
        axis.set_yticks(range(len(cases)), cases, fontsize="small")
        axis.invert_yaxis()
        axis.set_title(f"table {n + 1}: {name}" if len(tables) > 1 else name, fontsize="medium")
        axis.locator_params(axis="x", nbins=4)
        axis.grid(True, axis="x", alpha=0.3)
    for axis in axes.flat[len(panels) :]:
        axis.set_visible(False)
    figure.suptitle(
        "\n".join(f"{n + 1}. {t}" if len(tables) > 1 else t for n, (t, _, _) in enumerate(tables)),
        fontsize="small",
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=100, bbox_inches="tight")
    plt.close(figure)
    return True


def print_table(title: str, header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """Print and return an aligned table; with `--json`, each row as JSON; redraw the PNG."""
    cells = [[f"{c:.3f}" if isinstance(c, float) else str(c) for c in r] for r in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(header)]
    lines = [title, "  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True))]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in cells]
    text = "\n".join(lines)
    print(text, flush=True)
    if _settings.json:
        print("\n".join(json_rows(title, header, rows)), flush=True)
    if _settings.plot is not None:
        _settings.tables.append((title, list(header), [list(r) for r in rows]))
        if plot_tables(_settings.tables, _settings.plot) and not _settings.announced:
            _settings.announced = True
            print(f"plot: {_settings.plot}", flush=True)
    return text
