#!/usr/bin/env python3
"""The README is the front door and docs/ holds the rest; this keeps them honest.

Fails, listing every problem, when
  - README.md is longer than 200 lines (a front door: the rest is in docs/);
  - a relative link in README.md or docs/*.md names a file that does not exist, or a heading
    (#anchor) that its file does not have;
  - a page of docs/ is not linked from README.md;
  - a test that ctest knows (ctest -N in BUILD_DIR) is not named, in backticks, in docs/testing.md.

  tests/check_docs.py SOURCE_DIR BUILD_DIR
"""
import os
import re
import subprocess
import sys

README_MAX_LINES = 200
LINK = re.compile(r'\[[^\]]*\]\(([^)\s]+)\)')


def anchor_of(heading):
    """The anchor a Markdown renderer gives a heading: lower case, punctuation dropped, spaces -."""
    text = re.sub(r'[^\w\- ]', '', heading.strip().lower())
    return text.replace(' ', '-')


def anchors(path):
    found, in_code = set(), False
    with open(path, encoding='utf-8') as f:
        for line in f:
            if line.startswith('```'):
                in_code = not in_code
            elif not in_code and line.startswith('#'):
                found.add(anchor_of(line.lstrip('#')))
    return found


def links(path):
    with open(path, encoding='utf-8') as f:
        text = f.read()
    text = re.sub(r'```.*?```', '', text, flags=re.S)
    return [m.group(1) for m in LINK.finditer(text)]


def main():
    if len(sys.argv) != 3:
        sys.exit('usage: check_docs.py SOURCE_DIR BUILD_DIR')
    src, build = sys.argv[1], sys.argv[2]
    problems = []

    readme = os.path.join(src, 'README.md')
    with open(readme, encoding='utf-8') as f:
        lines = f.read().count('\n')
    if lines > README_MAX_LINES:
        problems.append(f'README.md has {lines} lines, more than {README_MAX_LINES}')

    docs_dir = os.path.join(src, 'docs')
    pages = sorted(p for p in os.listdir(docs_dir) if p.endswith('.md'))
    checked = [readme] + [os.path.join(docs_dir, p) for p in pages]
    for page in checked:
        rel = os.path.relpath(page, src)
        for target in links(page):
            if re.match(r'^[a-z]+:', target):  # http:, https:, mailto:
                continue
            file_part, _, frag = target.partition('#')
            dest = page if not file_part else os.path.normpath(
                os.path.join(os.path.dirname(page), file_part))
            if not os.path.exists(dest):
                problems.append(f'{rel}: link to {target}: no file {os.path.relpath(dest, src)}')
            elif frag and dest.endswith('.md') and frag not in anchors(dest):
                problems.append(f'{rel}: link to {target}: {os.path.relpath(dest, src)} has no heading #{frag}')

    readme_links = {os.path.normpath(t.partition('#')[0]) for t in links(readme)}
    for p in pages:
        if os.path.join('docs', p) not in readme_links:
            problems.append(f'docs/{p} is not linked from README.md')

    listed = subprocess.run(['ctest', '--test-dir', build, '-N'], capture_output=True, text=True,
                            check=True).stdout
    names = re.findall(r'Test +#\d+: (\S+)', listed)
    if not names:
        problems.append(f'ctest -N in {build} lists no test')
    with open(os.path.join(docs_dir, 'testing.md'), encoding='utf-8') as f:
        testing = f.read()
    for name in names:
        if f'`{name}`' not in testing:
            problems.append(f'docs/testing.md does not name the test `{name}`')

    for p in problems:
        print(p)
    if problems:
        print(f'{len(problems)} failed')
        return 1
    print(f'README.md {lines} lines; {len(checked)} pages with their links checked; '
          f'{len(names)} tests named in docs/testing.md')
    return 0


if __name__ == '__main__':
    sys.exit(main())
