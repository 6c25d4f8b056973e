"""The options of identify and select, as the library's option table describes them, against the
docs' option tables, the command line's --help and the Python signatures.

usage: option_docs.py SOURCE_DIR MOMENTID   (with the built Python module on PYTHONPATH)

For each command, the options of its section "## Options" in docs/cli/<command>.md (the first
cell of each table row, and the options a paragraph names) must be the long options that
`momentid <command> --help` lists; every option of the table must be among them, with the value
name the table gives it wherever the docs give one; and the keyword-only parameters of
momentid.<command> must be the table's keywords. Prints what differs and exits 1.
"""

import inspect
import re
import subprocess
import sys
from pathlib import Path

import momentid
from momentid import _momentid

CODE = re.compile(r"`([^`]+)`")


def options_section(path):
    """The lines of the "## Options" section of a docs page."""
    lines = path.read_text(encoding="utf-8").splitlines()
    start = lines.index("## Options") + 1
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("## ")), len(lines))
    return lines[start:end]


def documented(path):
    """{long option: value name or None} of a page's "## Options" section."""
    out = {}
    for line in options_section(path):
        if line.startswith("| --- ") or line.startswith("| option "):
            continue
        # A table row names its options in its first cell; a paragraph anywhere in it.
        text = line.split(" | ")[0] if line.startswith("|") else line
        for span in CODE.findall(text.replace("\\|", "|")):
            for part in span.split(", "):
                flag, _, value = part.partition(" ")
                if flag.startswith("--"):
                    out[flag] = value or out.get(flag)
    return out


def in_help(momentid_path, command):
    """{long option: value name} of `momentid COMMAND --help`."""
    text = subprocess.run([momentid_path, command, "--help"], capture_output=True, text=True,
                          check=True).stdout
    out = {}
    for line in text.splitlines():
        match = re.match(r"^  (-\S+)(?: (\S+))?", line)
        if not match:
            continue
        value = match.group(2)
        if value in (None, "Excludes:", "Needs:"):
            value = None
        for flag in match.group(1).split(","):
            if flag.startswith("--") and flag not in ("--help", "--version"):
                out[flag] = value
    return out


def problems(source, momentid_path, command):
    table = _momentid._options(command)
    docs = documented(source / "docs" / "cli" / f"{command}.md")
    cli = in_help(momentid_path, command)
    page = f"docs/cli/{command}.md"
    out = [f"{page} lacks {flag}" for flag in sorted(set(cli) - set(docs))]
    out += [f"{page} names {flag}, which `{command} --help` lacks"
            for flag in sorted(set(docs) - set(cli))]
    for option in table:
        flag, value = option["flag"], option["value_name"] or None  # a flag has none
        if cli.get(flag, value) != value:
            out.append(f"`{command} --help` shows {flag} {cli.get(flag)}, the table {value}")
        if flag not in cli:
            out.append(f"`{command} --help` lacks {flag} of the option table")
        if docs.get(flag) and docs[flag] != value:
            out.append(f"{page} writes {flag} {docs[flag]}, the option table {flag} {value}")
    keywords = [option["keyword"] for option in table]
    signature = inspect.signature(getattr(momentid, command))
    taken = [p.name for p in signature.parameters.values() if p.kind == p.KEYWORD_ONLY]
    if taken != keywords:
        out.append(f"momentid.{command}{signature} takes {taken}, the table {keywords}")
    doc = getattr(momentid, command).__doc__
    out += [f"help(momentid.{command}) does not describe {keyword}"
            for keyword in keywords if not re.search(rf"^\s+{keyword} \(", doc, re.M)]
    return out


def main():
    source, momentid_path = Path(sys.argv[1]), sys.argv[2]
    found = []
    for command in ("identify", "select"):
        found += problems(source, momentid_path, command)
    for line in found:
        print(line)
    if found:
        return 1
    print("the docs, --help and the Python signatures name every option of the table")
    return 0


if __name__ == "__main__":
    sys.exit(main())
