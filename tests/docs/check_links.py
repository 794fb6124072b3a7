#!/usr/bin/env python3
"""Checks that the project's Markdown pages link only to things that exist.

    python3 tests/docs/check_links.py REPO_ROOT

It reads README.md and every docs/**/*.md. For every Markdown link or image
`[text](target)`, reference definition `[label]: target` and HTML `<img src=...>`
whose target is relative (not http:, https:, mailto: or another scheme):

- the path must name an existing file or directory, relative to the Markdown file
  (a path starting with / is relative to the repository root), inside the repository;
- a `#anchor` must be the slug of a heading of the target Markdown file, or of the same
  file for `#anchor` alone. Slugs follow GitHub's rules: lowercase; every character that
  is not a letter, digit, space, hyphen or underscore removed; each space a hyphen; a
  repeated heading gets -1, -2, ... Anchors into files that are not Markdown are not checked.

Links inside fenced code blocks and inline code are examples, not links, and are skipped.
README.md is the front page, so it may have at most 250 lines.

It prints one line per broken link (file:line: target: why) and exits 1 if there is any
problem; otherwise it prints one line with the count and exits 0. Standard library only,
so that ctest can run it anywhere (tests/CMakeLists.txt, docs.links).
"""
import os
import re
import sys
import unicodedata
from urllib.parse import unquote

README_MAX_LINES = 250

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})(.*)$")
ATX_HEADING = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?(?:[ \t]+#+)?[ \t]*$")
SETEXT_UNDERLINE = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
CODE_SPAN = re.compile(r"(?<!`)(`+)(?!`)(.+?)(?<!`)\1(?!`)", re.DOTALL)
# [text](target "title"): the text may hold one level of brackets; the target may be in
# <...> or hold one level of balanced parentheses.
INLINE_LINK = re.compile(
    r"\[(?:[^\[\]]|\[[^\[\]]*\])*\]\(\s*(<[^>\n]*>|(?:[^()\s]|\([^()\s]*\))*)"
    r"(?:\s+(?:\"[^\"]*\"|'[^']*'|\([^()]*\)))?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:[ \t]*(<[^>\n]*>|\S+)", re.MULTILINE)
IMG_SRC = re.compile(r"<img\b[^>]*?\bsrc\s*=\s*(?:\"([^\"]*)\"|'([^']*)'|([^\s>]+))", re.IGNORECASE)
HTML_ID = re.compile(r"<a\b[^>]*?\b(?:name|id)\s*=\s*[\"']([^\"']+)[\"']", re.IGNORECASE)
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


def split_blocks(text):
    """The file's lines with fenced code blocks blanked (line numbers kept)."""
    lines = text.split("\n")
    out = []
    fence = None  # the opening fence's character and length while inside a fenced block
    for line in lines:
        match = FENCE.match(line)
        if fence is None:
            if match and not (match.group(1)[0] == "`" and "`" in match.group(2)):
                fence = (match.group(1)[0], len(match.group(1)))
                out.append("")
                continue
            out.append(line)
        else:
            if match and match.group(1)[0] == fence[0] and len(match.group(1)) >= fence[1] \
                    and not match.group(2).strip():
                fence = None
            out.append("")
    return out


def blank_code_spans(lines):
    """Inline code replaced by spaces, paragraph by paragraph (a code span may wrap a line
    but not cross a blank line); newlines are kept so offsets still give line numbers."""
    text = "\n".join(lines)
    paragraphs = re.split(r"(\n[ \t]*\n)", text)
    blanked = []
    for part in paragraphs:
        blanked.append(CODE_SPAN.sub(lambda m: re.sub(r"[^\n]", " ", m.group(0)), part))
    return "".join(blanked)


def heading_text_to_slug(text):
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"!?\[((?:[^\[\]]|\[[^\[\]]*\])*)\]\([^)]*\)", r"\1", text)  # links: their text
    text = re.sub(r"<[^>]+>", "", text)  # HTML tags
    text = text.strip().lower()
    kept = []
    for ch in text:
        category = unicodedata.category(ch)
        if ch in (" ", "-", "_") or category[0] in ("L", "N") or category[0] == "M":
            kept.append(ch)
    return "".join(kept).replace(" ", "-")


def anchors_of(path, cache={}):
    """Every anchor a Markdown file defines: its headings' slugs and HTML ids."""
    if path in cache:
        return cache[path]
    with open(path, encoding="utf-8") as f:
        lines = split_blocks(f.read())
    seen = {}
    anchors = set()

    def add(text):
        slug = heading_text_to_slug(text)
        count = seen.get(slug, 0)
        seen[slug] = count + 1
        anchors.add(slug if count == 0 else "%s-%d" % (slug, count))

    for i, line in enumerate(lines):
        heading = ATX_HEADING.match(line)
        if heading:
            add(heading.group(2) or "")
        elif SETEXT_UNDERLINE.match(line) and i > 0 and lines[i - 1].strip() \
                and not ATX_HEADING.match(lines[i - 1]) and not lines[i - 1].lstrip().startswith("|") \
                and not re.match(r"^ {0,3}([-*+]|\d+[.)])[ \t]", lines[i - 1]):
            add(lines[i - 1])
        for html_id in HTML_ID.findall(line):
            anchors.add(html_id)
    cache[path] = anchors
    return anchors


def targets_in(text):
    """(offset, target) of every link, image, reference definition and <img src>."""
    for match in INLINE_LINK.finditer(text):
        target = match.group(1)
        if target.startswith("<") and target.endswith(">"):
            target = target[1:-1]
        yield match.start(), target
    for match in REFERENCE_DEFINITION.finditer(text):
        target = match.group(1)
        if target.startswith("<") and target.endswith(">"):
            target = target[1:-1]
        yield match.start(), target
    for match in IMG_SRC.finditer(text):
        yield match.start(), next(g for g in match.groups() if g is not None)


def check_file(root, path):
    """The broken links of one Markdown file as (line, target, why), and how many links it has."""
    with open(path, encoding="utf-8") as f:
        text = blank_code_spans(split_blocks(f.read()))
    problems = []
    count = 0
    for offset, target in sorted(targets_in(text)):
        line = text.count("\n", 0, offset) + 1
        if not target or SCHEME.match(target) or target.startswith("//"):
            continue  # an external link (or an empty one, which Markdown shows as text)
        count += 1
        file_part, _, anchor = target.partition("#")
        file_part = unquote(file_part.split("?", 1)[0])
        if file_part:
            base = root if file_part.startswith("/") else os.path.dirname(path)
            resolved = os.path.normpath(os.path.join(base, file_part.lstrip("/")))
            if os.path.relpath(resolved, root).startswith(os.pardir):
                problems.append((line, target, "outside the repository"))
                continue
            if not os.path.exists(resolved):
                problems.append((line, target, "no such file or directory"))
                continue
        else:
            resolved = path
        if not anchor:
            continue
        if not (os.path.isfile(resolved) and resolved.endswith(".md")):
            continue  # an anchor into code or a directory: GitHub's line anchors, not checked
        if unquote(anchor) not in anchors_of(resolved):
            problems.append((line, target, "no heading with that anchor in %s" % os.path.relpath(resolved, root)))
    return problems, count


def markdown_files(root):
    files = [os.path.join(root, "README.md")]
    for directory, subdirectories, names in os.walk(os.path.join(root, "docs")):
        subdirectories.sort()
        files.extend(os.path.join(directory, name) for name in sorted(names) if name.endswith(".md"))
    return files


def main(argv):
    if len(argv) != 2:
        print("usage: check_links.py REPO_ROOT", file=sys.stderr)
        return 2
    root = os.path.abspath(argv[1])
    failed = False
    links = 0
    files = markdown_files(root)
    for path in files:
        if not os.path.isfile(path):
            print("%s: missing" % os.path.relpath(path, root))
            failed = True
            continue
        problems, count = check_file(root, path)
        links += count
        for line, target, why in problems:
            print("%s:%d: %s: %s" % (os.path.relpath(path, root), line, target, why))
            failed = True
    with open(os.path.join(root, "README.md"), encoding="utf-8") as f:
        readme_lines = len(f.read().splitlines())
    if readme_lines > README_MAX_LINES:
        print("README.md: %d lines, more than the front page's %d" % (readme_lines, README_MAX_LINES))
        failed = True
    if failed:
        return 1
    print("%d relative links in %d Markdown files: all resolve; README.md has %d lines"
          % (links, len(files), readme_lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
