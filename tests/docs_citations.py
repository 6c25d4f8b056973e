#!/usr/bin/python3
"""Checks that the documentation the sources cite exists.

Comments cite a page of the documentation by its path from the repository's top, optionally
with one of its headings: `(docs/uncertainty.md, "End values")` or `docs/json.md ("identify")`;
a citation may run on over a comment's next line. Every cited page must exist, and every cited
heading must be a heading of that page. The old form, which named a section of the README, is
refused: the README no longer holds those sections.

The documentation's own links to a heading, `[text](page.md#anchor)`, must name a heading of
that page too (MkDocs checks that pages exist, but not headings).

Usage: docs_citations.py [ROOT]   (default: the repository holding this file)
Exits 1 and lists each broken citation or link as `file:line: what`.
"""

import pathlib
import re
import sys
import unicodedata

SOURCE_DIRS = ("src", "include", "python", "tests", "benchmarks", "examples", "grammar", "cmake",
               ".ci")
SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".py", ".sh", ".cmake", ".txt", ".md", ".toml"}

# A page, then optionally its heading after a comma or in parentheses; between them and inside
# the heading a line may end and the next start with a comment leader.
_BREAK = r"(?:\s*\n\s*(?://|#)?)?\s*"
CITATION = re.compile(r"\b(docs/[\w./-]+?\.md)\b(?:" + r"(?:,|" + _BREAK + r"\()" + _BREAK +
                      r'"([^"]+)")?')
OLD_CITATION = re.compile(r'README(?:,|\s*\()\s*(?:(?://|#)\s*)?"[^"\n]+"')
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
ANCHOR_LINK = re.compile(r"\]\(([^)\s]*)#([^)\s]+)\)")


def headings(page):
    """The headings of a Markdown page, outside fenced code."""
    found, fenced = [], False
    for line in page.read_text(encoding="utf-8").splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced and (m := HEADING.match(line)):
            found.append(m.group(2))
    return found


def slug(heading):
    """The anchor MkDocs (Python-Markdown's toc) gives a heading; GitHub's agrees for headings
    of letters, digits, blanks, hyphens and backticks."""
    text = unicodedata.normalize("NFKD", heading).encode("ascii", "ignore").decode()
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def plain(text):
    """A heading as cited: blanks collapsed, comment leaders of a continued line removed."""
    text = re.sub(r"\s*\n\s*(?://|#)?\s*", " ", text)
    return " ".join(text.split())


def line_of(text, offset):
    return text.count("\n", 0, offset) + 1


def check_citations(root, path, text):
    problems = []
    for m in CITATION.finditer(text):
        page, heading = root / m.group(1), m.group(2)
        where = f"{path.relative_to(root)}:{line_of(text, m.start())}"
        if not page.is_file():
            problems.append(f"{where}: cites {m.group(1)}, which does not exist")
        elif heading is not None and plain(heading) not in headings(page):
            problems.append(f'{where}: cites "{plain(heading)}" in {m.group(1)}, which has no '
                            "such heading")
    for m in OLD_CITATION.finditer(text):
        where = f"{path.relative_to(root)}:{line_of(text, m.start())}"
        problems.append(f"{where}: cites a README section ({plain(m.group(0))}); cite the docs/ "
                        "page and heading")
    return problems


def check_anchors(root, page, text):
    problems = []
    for m in ANCHOR_LINK.finditer(text):
        target, anchor = m.group(1), m.group(2)
        if "://" in target:
            continue
        target_page = (page.parent / target).resolve() if target else page
        if target_page.suffix != ".md" or not target_page.is_file():
            continue  # a missing page is MkDocs' to report
        if anchor not in {slug(h) for h in headings(target_page)}:
            problems.append(f"{page.relative_to(root)}:{line_of(text, m.start())}: links to "
                            f"#{anchor} in {target or page.name}, which has no such heading")
    return problems


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else
                        pathlib.Path(__file__).resolve().parent.parent).resolve()
    problems = []
    for directory in SOURCE_DIRS:
        for path in sorted((root / directory).rglob("*")):
            if path.suffix in SOURCE_SUFFIXES and path.is_file():
                text = path.read_text(encoding="utf-8", errors="replace")
                problems += check_citations(root, path, text)
    for page in sorted((root / "docs").rglob("*.md")) + [root / "README.md"]:
        problems += check_anchors(root, page, page.read_text(encoding="utf-8"))
    for problem in problems:
        print(problem)
    print(f"docs citations: {len(problems)} broken")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
