#!/usr/bin/env python3
"""Checks that every relative link and image in the repository's Markdown
resolves: the file or folder exists, and a #fragment names a heading of the
target (GitHub's heading slugs). Web links are not fetched.

Usage: python3 tools/check_links.py [FILE.md ...]   (default: every tracked .md)
Exits 1 and lists the broken links if there are any.
"""
import os
import re
import subprocess
import sys

LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^(```|~~~)")


def slug(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped
    (hyphens and underscores kept), spaces to hyphens."""
    text = re.sub(r"`|\*|_(?=\W)|(?<=\W)_", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def prose_lines(path):
    """The file's lines outside fenced code blocks."""
    inside = False
    for line in open(path, encoding="utf-8"):
        if FENCE.match(line.lstrip()):
            inside = not inside
            continue
        if not inside:
            yield line


def anchors(path):
    found = set()
    for line in prose_lines(path):
        m = re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            base = slug(m.group(1))
            name, k = base, 1
            while name in found:
                name, k = f"{base}-{k}", k + 1
            found.add(name)
    return found


def broken_links(path):
    here = os.path.dirname(path)
    for n, line in enumerate(prose_lines(path), 1):
        # Inline code is not a link.
        for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):
                continue  # http:, https:, mailto:
            file_part, _, fragment = target.partition("#")
            dest = os.path.normpath(os.path.join(here, file_part)) if file_part else path
            if not os.path.exists(dest):
                yield f"{path}: {target}: no such file"
            elif fragment and dest.endswith(".md") and fragment not in anchors(dest):
                yield f"{path}: {target}: no heading #{fragment} in {dest}"


def main():
    files = sys.argv[1:] or subprocess.run(
        ["git", "ls-files", "*.md"], capture_output=True, text=True, check=True
    ).stdout.split()
    problems = [p for f in files for p in broken_links(f)]
    for p in problems:
        print(p)
    print(f"check_links: {len(files)} files, {len(problems)} broken link(s)")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
