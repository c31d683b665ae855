#!/usr/bin/env python3
"""Every link in README.md and docs/*.md resolves inside the repository (meson test 'links').

    tests/check_links.py SOURCE_DIR

For each inline Markdown link or image [text](target) outside code: a web address
(http, https, mailto) is not followed; any other target must be a file or directory of the
repository, relative to the page, and its #anchor (or a bare #anchor on the same page) must be
a heading of the target page, named as GitHub names it (lower case, punctuation dropped, spaces
to hyphens, -1, -2 ... for repeats). No page, and no source, header, script, scene or build
file of the repository, may name the team's private notes (DESIGN.md, REFERENCES.md,
../shared): the documentation stands alone.
Prints each broken link as FILE:LINE: target: why; exits 1 when there is one."""
import os
import re
import sys

LINK = re.compile(r'!?\[(?:[^\]\\]|\\.)*\]\(\s*<?([^)\s>]+)>?(?:\s+"[^"]*")?\s*\)')
PRIVATE = re.compile(r'(?<![\w/.-])(DESIGN\.md|REFERENCES\.md)|\.\./shared')


def prose_lines(text):
    """(line number, line with code spans blanked, raw line) outside fenced and indented code."""
    fence = None
    prev_blank = True
    for no, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        m = re.match(r'(```+|~~~+)', stripped)
        if fence:
            if m and stripped.startswith(fence):
                fence = None
            prev_blank = False
            continue
        if m:
            fence = m.group(1)
            continue
        if line.startswith('    ') and prev_blank:
            continue   # an indented code block (its following lines too while indented)
        prev_blank = not line.strip()
        yield no, re.sub(r'`[^`]*`', lambda s: ' ' * len(s.group(0)), line), line


def anchors(path, cache={}):
    if path not in cache:
        seen, out = {}, set()
        with open(path, encoding='utf-8') as f:
            for _, _, raw in prose_lines(f.read()):
                m = re.match(r'\s{0,3}#{1,6}\s+(.*?)\s*#*\s*$', raw)
                if not m:
                    continue
                title = m.group(1)
                slug = re.sub(r'[^\w\- ]', '', title.lower().replace('`', '')).replace(' ', '-')
                n = seen.get(slug, 0)
                seen[slug] = n + 1
                out.add(slug if n == 0 else f'{slug}-{n}')
        cache[path] = out
    return cache[path]


def check(root, page, problems):
    text = open(page, encoding='utf-8').read()
    rel = os.path.relpath(page, root)
    for no, line, raw in prose_lines(text):
        m = PRIVATE.search(raw)
        if m:
            problems.append(f'{rel}:{no}: names {m.group(0)}, the team\'s private notes')
        for target in LINK.findall(line):
            if re.match(r'[a-z][a-z0-9+.-]*:', target):
                continue   # http:, https:, mailto:
            path, _, frag = target.partition('#')
            dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
            if not os.path.abspath(dest).startswith(os.path.abspath(root) + os.sep):
                problems.append(f'{rel}:{no}: {target}: outside the repository')
            elif not os.path.exists(dest):
                problems.append(f'{rel}:{no}: {target}: no such file')
            elif frag and not dest.endswith('.md'):
                problems.append(f'{rel}:{no}: {target}: an anchor in a file that is not Markdown')
            elif frag and frag not in anchors(dest):
                problems.append(f'{rel}:{no}: {target}: no heading #{frag} in '
                                f'{os.path.relpath(dest, root)}')


TEXT = ('.c', '.h', '.cc', '.md', '.py', '.yaml', '.yml', '.build', '.txt', '.sh', '.csv')


def check_sources(root, problems):
    """Files outside docs/ and README.md (those are checked line by line with their links)."""
    for d, dirs, files in os.walk(root):
        dirs[:] = [x for x in dirs if not x.startswith(('build', '.')) and x != 'crashes']
        for f in files:
            path = os.path.join(d, f)
            rel = os.path.relpath(path, root)
            if (not f.endswith(TEXT) and not rel.startswith(('scripts', '.ci'))) or \
                    rel in ('tests/check_links.py', 'README.md') or rel.startswith('docs'):
                continue
            try:
                lines = open(path, encoding='utf-8').read().splitlines()
            except (UnicodeDecodeError, OSError):
                continue
            for no, line in enumerate(lines, 1):
                m = PRIVATE.search(line)
                if m:
                    problems.append(f'{rel}:{no}: names {m.group(0)}, the team\'s private notes')


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else '.')
    docs = os.path.join(root, 'docs')
    pages = [os.path.join(root, 'README.md')] + sorted(
        os.path.join(docs, f) for f in os.listdir(docs) if f.endswith('.md'))
    problems, links = [], 0
    for page in pages:
        for _, line, _ in prose_lines(open(page, encoding='utf-8').read()):
            links += len(LINK.findall(line))
        check(root, page, problems)
    check_sources(root, problems)
    for p in problems:
        print(p)
    print(f'links: {len(pages)} pages, {links} links, {len(problems)} broken')
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
