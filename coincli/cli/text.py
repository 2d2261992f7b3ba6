"""Line breaking for the terminal that never splits a number from its name or its unit.

Rich wraps at any space, so at 80 columns "y0 = 0.0100499 m" could end a line at "y0 =" and
"phi = 9.6 rad" could lose its unit. These helpers break only between phrases: a word is glued
to "=" or "->" on either side, to a unit after it and to the number after "eq." or "fig.",
and the breaks become explicit newlines
that rich then has no reason to move. A caller marks a phrase of its own with no-break spaces
(NBSP), which are never broken and print as spaces.
"""

from __future__ import annotations

import math
import re
import shlex

UNITS = frozenset({"m", "mm", "um", "m/s", "rad", "rad/s", "deg", "s", "ms", "mJ", "N/m", "N",
                   "kg", "g", "%", "cells", "cells/s", "tiles", "traj/s", "trajectories/s", "MB"})
GLUE = frozenset({"=", "->", "<", ">", "<=", ">=", "+-", "~"})
BEFORE_NUMBER = frozenset({"eq", "eqs", "fig", "figs", "section", "tile"})
NBSP = "\u00a0"
_SPACES = re.compile(r"( +)")  # ASCII spaces only: NBSP never breaks
_TAG = re.compile(r"\[/?[a-z][a-z \u00a0]*\]|\[/\]")  # rich markup: [bold], [bold red], [/]


def _visible(markup: str) -> int:
    return len(_TAG.sub("", markup))


def _bare(word: str) -> str:
    """A word without markup and the punctuation that may follow a unit."""
    return _TAG.sub("", word).strip("()[],;:.")


def _glued(left: str, right: str) -> bool:
    left, right = _bare(left), _bare(right)
    times = (right == "x" and left[-1:].isdigit()) or (left == "x" and right[:1].isdigit())
    return (times or left in GLUE or left in BEFORE_NUMBER or right in GLUE or right in UNITS)


def keep_whole(text: str, width: int, indent: int = 0) -> str:
    """`text` broken into lines of at most `width` cells, only between phrases.

    Continuation lines are indented by `indent` spaces; a phrase longer than a line stays whole
    (the terminal folds it). Markup is kept; widths count only what is shown.
    """
    text = _TAG.sub(lambda tag: tag.group(0).replace(" ", NBSP), text)  # a tag is no phrase
    parts = _SPACES.split(text)
    words, seps = parts[0::2], parts[1::2]
    phrases, joins = [words[0]], []
    for sep, word in zip(seps, words[1:], strict=True):
        if _glued(phrases[-1].rsplit(" ", 1)[-1], word):
            phrases[-1] += sep + word
        else:
            phrases.append(word)
            joins.append(sep)
    lines, line, used = [], phrases[0], _visible(phrases[0])
    for sep, phrase in zip(joins, phrases[1:], strict=True):
        size = _visible(phrase)
        if used + len(sep) + size <= width:
            line, used = line + sep + phrase, used + len(sep) + size
        else:
            lines.append(line)
            line, used = " " * indent + phrase, indent + size
    lines.append(line)
    return "\n".join(lines).replace(NBSP, " ")


LABEL_WIDTH = 12  # the widest label, "final state", and a space


def clock(seconds: float) -> str:
    """84.3 -> '1:24' (minutes and seconds, as a progress bar's clock shows them)."""
    minutes, secs = divmod(round(seconds), 60)
    return f"{minutes}:{secs:02d}"


def counted(count: int, noun: str, plural: str | None = None) -> str:
    """'1 tile', '2 tiles', '1,024 cells'."""
    return f"{count:,} {noun if count == 1 else plural or noun + 's'}"


def command(*words) -> str:
    """A command to copy from the terminal: quoted for the shell, one phrase, never broken."""
    return NBSP.join(shlex.quote(str(word)).replace(" ", NBSP) for word in words)


def line_width(console) -> int | None:
    """The width to break paragraphs at: the terminal's, or None when the output is no
    terminal (a pipe, a file, a test's capture), where a paragraph stays one line for grep and
    logs, whatever width the terminal the command was started from has."""
    return console.width if console.is_terminal else None


def say(console, text: str, indent: int = 0) -> None:
    """Print a paragraph, broken between phrases at a terminal's width."""
    width = line_width(console)
    if width is not None:
        text = keep_whole(text, width, indent)
    console.print(text.replace(NBSP, " "), highlight=False, soft_wrap=True)


def print_rows(console, rows, label_width: int | None = None) -> None:
    """Label and value rows, each value broken between phrases to fit a terminal."""
    if label_width is None:
        label_width = max(len(label) for label, _ in rows) + 1
    width = line_width(console)
    for label, value in rows:
        if width is not None:
            value = keep_whole(value, max(width - label_width, 20), indent=label_width)
        console.print(f"[bold]{label:<{label_width}}[/]{value.replace(NBSP, ' ')}",
                      highlight=False, soft_wrap=True)


def print_table(console, table, title: str) -> None:
    """A table under its title, the title broken between phrases (as a table's own title,
    rich would break '95 %' after the number)."""
    say(console, f"[italic]{title}[/italic]")
    console.print(table)


TOP_OUTCOMES = 10  # the outcomes an outcome table lists without --all


def most_frequent(rows: list, most: int = TOP_OUTCOMES) -> tuple[list, list]:
    """The rows of the ``most`` highest ``count`` in their own order (by n), and the rows left
    out. Rows of one count are kept or left out together (a mirrored map's n and -n have as
    many cells: both are listed, or neither): the rows tied at the cut are kept when they
    overrun ``most`` by at most half as many again, else left out; only when every row kept
    would be one of them are the earliest ``most`` kept."""
    if len(rows) <= most:
        return list(rows), []
    counts = sorted((row["count"] for row in rows), reverse=True)
    cut = counts[most - 1]
    above = sum(count > cut for count in counts)
    tied = counts.count(cut)
    if above + tied <= most + most // 2:
        kept = {i for i, row in enumerate(rows) if row["count"] >= cut}
    elif above:
        kept = {i for i, row in enumerate(rows) if row["count"] > cut}
    else:  # a tie too many to list: the earliest
        kept = set(sorted(range(len(rows)), key=lambda i: (-rows[i]["count"], i))[:most])
    return ([row for i, row in enumerate(rows) if i in kept],
            [row for i, row in enumerate(rows) if i not in kept])


def left_out(rows: list, share: float, of: str) -> str:
    """The line under an outcome table that lists only the most frequent: '... 72 more n,
    0.8 % of the labelled cells together (--all lists every n)'."""
    return (f"... {len(rows)} more n, {percent(share)} of the {of} together (--all lists "
            "every n)")


# -- numbers as the tables print them -----------------------------------------------------------
TURN = {"none": "none", "clockwise": "cw", "counter-clockwise": "ccw"}  # table column "turn"


def percent(x, digits: int = 3) -> str:
    """0.00294 -> '0.294 %'; 0.99711 -> '99.711 %' (above one half, the distance to 100 % gets
    the digits), never a rounded '100 %' or '0 %' for a fraction that is not exactly 1 or 0;
    None or NaN -> '-'."""
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if 0.5 < x < 1:  # near 100 %, the distance to 100 % gets the significant digits
        decimals = max(0, digits - 1 - math.floor(math.log10(100 * (1 - x)) + 1e-9))
        return f"{100 * x:.{decimals}f} %"
    text = f"{100 * x:.{digits}g}"
    while digits < 12 and ((text == "100" and x < 1) or (float(text) == 0 and x > 0)):
        digits += 1
        text = f"{100 * x:.{digits}g}"
    return f"{text} %"


def resolving(p: dict, digits: int = 3) -> int:
    """The significant digits that tell a proportion's interval ends apart (at least
    ``digits``): '15.8 % to 15.8 %' becomes '15.75 % to 15.83 %'."""
    while digits < 8 and percent(p["low"], digits) == percent(p["high"], digits) and \
            p["low"] != p["high"]:
        digits += 1
    return digits


def interval(p: dict, digits: int = 3) -> str:
    """A proportion's 95 % interval: '0.274 % to 0.315 %'."""
    digits = resolving(p, digits)
    return f"{percent(p['low'], digits)} to {percent(p['high'], digits)}"


def share(p: dict, digits: int = 3) -> str:
    """A proportion (see coincli.stats.proportion): '770 of 262,144 = 0.294 % (95 % CI 0.274 %
    to 0.315 %)'."""
    digits = resolving(p, digits)
    return (f"{p['count']:,} of {p['of']:,} = {percent(p['probability'], digits)} "
            f"(95 % CI {interval(p, digits)})")
