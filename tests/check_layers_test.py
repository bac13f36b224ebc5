#!/usr/bin/env python3
"""tests/check_layers.py on the real tree, then on copies of it with one include broken: an
upward include, an include across to a sibling room, a file outside every room, an env that
includes an optimizer, and a SQL statement in a command must each fail naming the file and line;
a tree without the table exits 2.

  tests/check_layers_test.py SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CHECK = os.path.join(HERE, 'check_layers.py')
FOLDERS = ['common', 'envs', 'optimizers', 'render', 'reference', 'harness', 'python', 'tools', 'tests']


def run(root):
    r = subprocess.run([sys.executable, CHECK, root], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def copy_tree(source, dest):
    keep = ('.cpp', '.hpp', '.cpp.in')
    ignore = lambda folder, names: [n for n in names
                                    if not os.path.isdir(os.path.join(folder, n)) and not n.endswith(keep)]
    for f in FOLDERS:
        shutil.copytree(os.path.join(source, f), os.path.join(dest, f), ignore=ignore)
    os.makedirs(os.path.join(dest, 'docs'))
    shutil.copy(os.path.join(source, 'docs', 'layout.md'), os.path.join(dest, 'docs', 'layout.md'))


def append(root, rel, text):
    with open(os.path.join(root, rel), 'a', encoding='utf-8') as f:
        f.write(text)
    with open(os.path.join(root, rel), encoding='utf-8') as f:
        return sum(1 for _ in f)  # the line just added


def main(source):
    failures = []

    def expect(ok, what):
        print(('ok   ' if ok else 'FAIL ') + what)
        if not ok:
            failures.append(what)

    code, out = run(source)
    expect(code == 0, f'the tree itself passes (exit {code})')
    if code != 0:
        print(out)

    # each case: (file, the include added, words the failure must name)
    cases = [
        ('harness/store/store.cpp', '#include "harness/plan/plan.hpp"\n', 'harness/store/ may not include harness/plan/'),
        ('harness/run/runner.hpp', '#include "harness/commands/grid_args.hpp"\n',
         'harness/run/ may not include harness/commands/'),
        ('harness/plan/plan.cpp', '#include "harness/store/store.hpp"\n', 'harness/plan/ may not include harness/store/'),
        ('harness/core/run_key.hpp', '#include "harness/run/budget.hpp"\n', 'harness/core/ may not include harness/run/'),
        ('envs/registry.cpp', '#include "optimizers/registry.hpp"\n', 'envs/ may not include optimizers/'),
        ('common/rng.hpp', '#include "harness/core/run_key.hpp"\n', 'common/ may not include harness/core/'),
    ]
    for rel, include, words in cases:
        with tempfile.TemporaryDirectory() as tmp:
            copy_tree(source, tmp)
            line = append(tmp, rel, include)
            code, out = run(tmp)
            expect(code == 1 and f'{rel}:{line}:' in out and words in out,
                   f'{include.strip()} added to {rel}: exit {code}, names {rel}:{line} and "{words}"')
            if code != 1:
                print(out)

    with tempfile.TemporaryDirectory() as tmp:
        copy_tree(source, tmp)
        with open(os.path.join(tmp, 'harness', 'helper.hpp'), 'w') as f:
            f.write('#pragma once\n')
        line = append(tmp, 'harness/commands/cli.cpp', '#include "harness/helper.hpp"\n')
        code, out = run(tmp)
        expect(code == 1 and 'harness/helper.hpp: in no room' in out and f'harness/commands/cli.cpp:{line}:' in out,
               f'a file beside the rooms and its include: exit {code}, both named')

    with tempfile.TemporaryDirectory() as tmp:
        copy_tree(source, tmp)
        line = append(tmp, 'harness/commands/export_command.cpp',
                      'static const char* kCount = "SELECT COUNT(*) FROM runs";\n')
        code, out = run(tmp)
        expect(code == 1 and f'harness/commands/export_command.cpp:{line}: SQL outside harness/store/' in out,
               f'a SELECT in a command: exit {code}, names harness/commands/export_command.cpp:{line}')

    with tempfile.TemporaryDirectory() as tmp:
        copy_tree(source, tmp)
        with open(os.path.join(tmp, 'docs', 'layout.md'), 'w') as f:
            f.write('# Layout\n')
        code, out = run(tmp)
        expect(code == 2, f'no table in docs/layout.md: exit {code}')

    print(f'check_layers_test: {len(failures)} failed' if failures else 'check_layers_test: all passed')
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
