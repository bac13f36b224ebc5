#!/usr/bin/env python3
"""Includes run only downward: every `#include "..."` of the C++ sources against the table of
allowed layers in docs/layout.md ("Layers").

The table's rows name a folder and the folders its files may include. A file belongs to the row
of the longest folder that holds it; an include to the row of the longest folder its path starts
with (an include under no row, such as the generated git_sha.hpp, is not checked). Fails, listing
each one as FILE:LINE, when
  - a file includes a folder its row does not allow (up a layer, or across to a sibling);
  - a source file, or an include, lies in a folder that has rooms in the table but in none of them
    (harness/x.hpp beside harness/store/, ...);
  - a file of harness/ outside harness/store/ holds SQL: a string literal that starts a statement
    (SELECT, INSERT, UPDATE, DELETE, CREATE, DROP, ALTER, PRAGMA, ATTACH, BEGIN, COMMIT). All SQL
    lives in the store.

  tests/check_layers.py SOURCE_DIR
Exit 0: every include is allowed; 1: not (each offence listed); 2: no table in docs/layout.md.
"""
import os
import re
import sys

BEGIN, END = '<!-- layers: begin -->', '<!-- layers: end -->'
ROW = re.compile(r'^\|\s*`([^`]+)`\s*\|(.*)\|\s*$')
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
SOURCES = ('.cpp', '.hpp', '.cpp.in')
SQL = re.compile(r'"\s*(SELECT|INSERT|UPDATE|DELETE|CREATE|DROP|ALTER|PRAGMA|ATTACH|BEGIN|COMMIT)\b')
SQL_HOME = 'harness/store/'


def read_table(layout_md):
    """{folder: set of folders it may include}, from the rows between the markers."""
    with open(layout_md, encoding='utf-8') as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        return None
    table = {}
    for line in text.split(BEGIN, 1)[1].split(END, 1)[0].splitlines():
        m = ROW.match(line)
        if m:
            table[m.group(1)] = set(re.findall(r'`([^`]+)`', m.group(2)))
    return table


def row_of(path, table):
    """The longest folder of the table that holds path, or None."""
    best = None
    for folder in table:
        if path.startswith(folder) and (best is None or len(folder) > len(best)):
            best = folder
    return best


def roomless(path, table):
    """True when path lies under a folder that has rooms in the table, but in none of them."""
    return row_of(path, table) is None and any(folder.startswith(path.split('/')[0] + '/') for folder in table)


def check(root):
    table = read_table(os.path.join(root, 'docs', 'layout.md'))
    if not table:
        print(f'check_layers: docs/layout.md has no table between {BEGIN} and {END}')
        return 2
    problems = []
    for top in sorted({folder.split('/')[0] for folder in table}):
        for folder, _, files in os.walk(os.path.join(root, top)):
            for name in sorted(files):
                if not name.endswith(SOURCES):
                    continue
                rel = os.path.relpath(os.path.join(folder, name), root).replace(os.sep, '/')
                own = row_of(rel, table)
                if own is None:
                    if roomless(rel, table):
                        problems.append(f'{rel}: in no room of the table (docs/layout.md, "Layers")')
                    continue
                with open(os.path.join(root, rel), encoding='utf-8', errors='replace') as f:
                    for number, line in enumerate(f, 1):
                        if rel.startswith('harness/') and not rel.startswith(SQL_HOME) and SQL.search(line):
                            problems.append(f'{rel}:{number}: SQL outside {SQL_HOME} (docs/layout.md, "Layers")')
                        m = INCLUDE.match(line)
                        if not m:
                            continue
                        target = m.group(1)
                        to = row_of(target, table)
                        if to is None:
                            if roomless(target, table):
                                problems.append(f'{rel}:{number}: includes "{target}", which is in no room')
                            continue
                        if to != own and to not in table[own]:
                            problems.append(f'{rel}:{number}: includes "{target}": {own} may not include {to} '
                                            f'(docs/layout.md, "Layers", allows {", ".join(sorted(table[own]))})')
    for p in problems:
        print(p)
    if problems:
        print(f'check_layers: {len(problems)} includes against the layers, or SQL outside the store')
        return 1
    print(f'check_layers: every include of {", ".join(sorted({f.split("/")[0] for f in table}))} runs as '
          f'docs/layout.md allows ({len(table)} rows)')
    return 0


if __name__ == '__main__':
    if len(sys.argv) != 2:
        print('usage: check_layers.py SOURCE_DIR', file=sys.stderr)
        sys.exit(2)
    sys.exit(check(sys.argv[1]))
