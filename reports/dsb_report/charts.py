"""What a report chart is: one declaration (plots.CHARTS) that build.py draws and index.html places.

A chart is drawn once per env section (PER_ENV: one per env and budget, from an EnvView) or once
for the report (ACROSS: the "Across envs" section, from an AcrossView). Its file name, alt text and
caption may name the fields {slug} (the env section's file stem), {env} (the env's name) and
{scale} (the sentence saying what the env's y axis shows, captions.SCALE_*); ACROSS charts have
none of them, so their texts hold no braces.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, NamedTuple

PER_ENV = "per env"   # in each env's section of index.html, above the render and the table
ACROSS = "across"     # in "Across envs", each followed by the table html.py gives its name, if any
SECTIONS = (PER_ENV, ACROSS)


@dataclass(frozen=True)
class EnvView:
    """What a PER_ENV chart draws from: one env at one budget."""
    panel: object        # data.Panel: the env's runs, best-so-far matrices [runs, budget]
    table: object        # pandas DataFrame of stats.final_table: one row per optimizer
    pal: dict            # optimizer -> (colour, line style), style.palette
    ys: object           # style.YScale of the env: linear, log, shifted or regret
    marks: dict          # optimizer -> marker, style.markers


@dataclass(frozen=True)
class AcrossView:
    """What an ACROSS chart draws from: every env's largest budget (data.main_panels)."""
    mean_ranks: object   # DataFrame of stats.mean_ranks: optimizer, episodes, mean_rank, n_envs
    ecdf: object         # DataFrame of stats.ecdf: optimizer, episodes, fraction_solved, n_triples
    pal: dict            # optimizer -> (colour, line style)
    n_envs: int          # the envs ranked and profiled


@dataclass(frozen=True)
class Chart:
    """One figure of the report, declared once in plots.CHARTS."""
    name: str                          # what it shows, one word, unique
    section: str                       # where index.html places it: PER_ENV or ACROSS
    png: str                           # its file name in the report folder ("curves_{slug}.png")
    draw: Callable[[object, str], object]   # draw(view, path): writes the PNG at path
    alt: str                           # the image's alt text
    caption: str                       # the text under it: how to read it


class Figure(NamedTuple):
    """A drawn chart as index.html shows it."""
    name: str
    png: str
    alt: str
    caption: str


def check(charts) -> None:
    """Raises ValueError naming the chart whose declaration is wrong: a name used twice, an unknown
    section, a PER_ENV file name without {slug} (two envs would write the same file) or a file name
    with another field."""
    seen = set()
    for c in charts:
        if c.name in seen:
            raise ValueError(f"chart '{c.name}' is declared twice")
        seen.add(c.name)
        if c.section not in SECTIONS:
            raise ValueError(f"chart '{c.name}': section '{c.section}' is not one of {', '.join(SECTIONS)}")
        if c.section == PER_ENV and "{slug}" not in c.png:
            raise ValueError(f"chart '{c.name}': png '{c.png}' of a per-env chart does not name {{slug}}")
        if "{" in c.png.replace("{slug}", "") or "}" in c.png.replace("{slug}", ""):
            raise ValueError(f"chart '{c.name}': png '{c.png}' may name no field but {{slug}}")


def draw(charts, section: str, view, path: Callable[[str], str], **fields) -> list:
    """Draws every chart of `section`, in declaration order, from `view` into path(file name) and
    returns their Figures; `fields` fill the {slug}, {env} and {scale} of their texts."""
    out = []
    for c in charts:
        if c.section != section:
            continue
        png = c.png.format(**fields)
        c.draw(view, path(png))
        out.append(Figure(c.name, png, c.alt.format(**fields), c.caption.format(**fields)))
    return out


def named(charts, name: str) -> Chart:
    """The chart declared as `name` (KeyError naming it when there is none)."""
    for c in charts:
        if c.name == name:
            return c
    raise KeyError(f"no chart named '{name}'")


def writes(charts, name: str) -> bool:
    """Whether `name` is a file that a chart of `charts` writes (for a PER_ENV chart, any env's):
    make_report.py removes such a file that the new report did not write (an env gone)."""
    return any(re.fullmatch(".+".join(re.escape(part) for part in c.png.split("{slug}")), name)
               for c in charts)
