#!/usr/bin/env python3
"""Check the relative links and images of the documentation.

Usage: python3 tools/check_docs.py [FILE.md ...]

Without arguments it checks README.md, docs/*.md and scenarios/README.md. Every Markdown link
`[text](target)`, image `![alt](target)`, reference definition `[label]: target` and HTML
`href`/`src` whose target is relative must point at an existing file or directory (relative to
the Markdown file), and a `#anchor` (alone, or after a `.md` target) must name a heading of that
file under GitHub's slug rules (lower case; letters, digits, `_`, `-` and spaces kept, spaces
turned into `-`; a repeated heading gets `-1`, `-2`, ...) or an HTML `id`/`name`. Links with a
scheme (`https:`, `mailto:`, ...) are not followed: no network. Fenced code blocks and inline code
are skipped.

Exit status 0 when every link resolves, 1 otherwise, with `file:line: message` for each broken
link on stderr. Standard library only.
"""

import os
import re
import sys
import unicodedata

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

FENCE = re.compile(r"^\s{0,3}(`{3,}|~{3,})")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
INLINE_CODE = re.compile(r"(`+)(.+?)\1")
# [text](target) and ![alt](target); the text may hold brackets one level deep.
INLINE_LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>]*>|[^)\s]*)(?:\s+(?:\"[^\"]*\"|'[^']*'))?\s*\)")
REF_DEF = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
HTML_ATTR = re.compile(r"""<(?:a|img|source)\b[^>]*?\b(?:href|src)\s*=\s*["']([^"']+)["']""", re.I)
HTML_ID = re.compile(r"""<[a-z]+\b[^>]*?\b(?:id|name)\s*=\s*["']([^"']+)["']""", re.I)
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def heading_text(raw):
    """The text GitHub renders for a heading's Markdown source."""
    text = INLINE_CODE.sub(lambda m: m.group(2).strip(), raw)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML tags
    return text


def slug(text):
    """GitHub's anchor for a heading text (before de-duplication)."""
    out = []
    for ch in text.lower():
        if ch in " -":
            out.append(ch)
        elif unicodedata.category(ch)[0] in "LMN" or unicodedata.category(ch) == "Pc":
            out.append(ch)
    return "".join(out).replace(" ", "-")


def scan(path):
    """Links (line, target) and anchors of one Markdown file."""
    links, anchors, counts = [], set(), {}
    in_fence = None
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    for number, line in enumerate(lines, 1):
        m = FENCE.match(line)
        if in_fence:
            if m and m.group(1)[0] == in_fence[0] and len(m.group(1)) >= len(in_fence):
                in_fence = None
            continue
        if m:
            in_fence = m.group(1)
            continue
        for idm in HTML_ID.finditer(line):
            anchors.add(idm.group(1))
        h = HEADING.match(line)
        if h:
            base = slug(heading_text(h.group(2)))
            n = counts.get(base, 0)
            counts[base] = n + 1
            anchors.add(base if n == 0 else f"{base}-{n}")
        code_free = INLINE_CODE.sub(lambda m: " " * len(m.group(0)), line)
        for lm in INLINE_LINK.finditer(code_free):
            links.append((number, lm.group(1)))
        r = REF_DEF.match(code_free)
        if r:
            links.append((number, r.group(1)))
        for am in HTML_ATTR.finditer(code_free):
            links.append((number, am.group(1)))
    return links, anchors


def main(argv):
    if argv:
        files = [os.path.abspath(a) for a in argv]
    else:
        docs = os.path.join(ROOT, "docs")
        files = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "scenarios", "README.md")]
        files += sorted(os.path.join(docs, n) for n in os.listdir(docs) if n.endswith(".md"))
    cache = {}

    def info(path):
        if path not in cache:
            cache[path] = scan(path)
        return cache[path]

    broken, checked = [], 0
    for md in files:
        rel_md = os.path.relpath(md, ROOT)
        if not os.path.isfile(md):
            broken.append(f"{rel_md}:0: file not found")
            continue
        links, _ = info(md)
        for number, target in links:
            target = target.strip("<>")
            if not target or SCHEME.match(target) or target.startswith("//"):
                continue
            checked += 1
            path_part, _, anchor = target.partition("#")
            path_part = path_part.split("?", 1)[0]
            if path_part:
                dest = os.path.normpath(os.path.join(os.path.dirname(md), path_part))
                if not os.path.exists(dest):
                    broken.append(f"{rel_md}:{number}: `{target}`: no such file or directory")
                    continue
            else:
                dest = md
            if anchor and dest.endswith(".md") and os.path.isfile(dest):
                if anchor not in info(dest)[1]:
                    where = os.path.relpath(dest, ROOT)
                    broken.append(f"{rel_md}:{number}: `{target}`: no heading `#{anchor}` in {where}")
    for b in broken:
        print(b, file=sys.stderr)
    if broken:
        print(f"check_docs: {len(broken)} broken link(s) of {checked} in {len(files)} file(s)", file=sys.stderr)
        return 1
    print(f"check_docs: {checked} relative links in {len(files)} files resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
