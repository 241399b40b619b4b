#!/usr/bin/env python3
"""Checks every relative link and image in the repository's Markdown files: the file must exist
and, for `file.md#anchor` or `#anchor`, the anchor must be a heading of that file (GitHub's
slugs: lower case, punctuation other than `-` and `_` dropped, spaces to `-`).

    python3 tools/check_md_links.py          # exit 1 and one line per broken link

External links (http, https, mailto) are not fetched.
"""

import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^\s*```")


def slug(heading: str) -> str:
    s = heading.strip().lower()
    s = re.sub(r"[^\w\- ]", "", s)
    return s.replace(" ", "-")


def anchors(path: pathlib.Path) -> set:
    out, seen, fenced = set(), {}, False
    for line in path.read_text(encoding="utf-8").splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        m = re.match(r"^#{1,6}\s+(.*)$", line)
        if m and not fenced:
            s = slug(m.group(1))
            n = seen.get(s, 0)
            seen[s] = n + 1
            out.add(s if n == 0 else f"{s}-{n}")
    return out


def links(path: pathlib.Path):
    fenced = False
    for no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            for m in LINK.finditer(line):
                yield no, m.group(1)


def main() -> int:
    bad = 0
    files = [p for p in ROOT.rglob("*.md")
             if not any(part in ("target", ".git", "out", "node_modules") for part in p.parts)]
    for md in sorted(files):
        for no, target in links(md):
            if re.match(r"^[a-z]+:", target):
                continue
            file_part, _, anchor = target.partition("#")
            dest = md if not file_part else (md.parent / file_part).resolve()
            where = f"{md.relative_to(ROOT)}:{no}: {target}"
            if not dest.exists():
                print(f"{where}: no such file")
                bad += 1
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                print(f"{where}: no heading #{anchor} in {dest.relative_to(ROOT)}")
                bad += 1
    print(f"{len(files)} Markdown files checked, {bad} broken links")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
