"""MkDocs hook: the pages link to files of the repository outside docs/ (an example's README,
its plot, the grammar) by relative paths, so that the links work when the pages are read in the
repository. MkDocs only knows the files under docs/ and would call those links broken; this hook
adds each linked file that exists to the site, under the same relative place, so the links work
there too. A linked file that does not exist is left out, and `mkdocs build --strict` fails on it.
"""

import os
import posixpath
import re

from mkdocs.structure.files import File

# A Markdown link or image target: ](path) or ](path "title"), up to a blank, '#' or ')'.
_LINK = re.compile(r"\]\(([^)\s#]+)")


class RepositoryFile(File):
    """A file outside docs/ copied into the site as it is (a Markdown file is not rendered: its
    own links are relative to its place in the repository, which the site does not mirror)."""

    def __init__(self, src_uri, docs_dir, site_dir):
        super().__init__(src_uri, docs_dir, site_dir, use_directory_urls=False)
        # "../examples/a.png" is served as "repository/examples/a.png".
        self.dest_uri = posixpath.join("repository", src_uri.removeprefix("../"))
        self.abs_dest_path = os.path.normpath(os.path.join(site_dir, self.dest_path))
        self.url = self.dest_uri

    def is_documentation_page(self):
        return False


def _outside_targets(page_uri, text):
    """The targets of the page's relative links that leave docs/, as paths from docs/."""
    for match in _LINK.finditer(text):
        target = match.group(1)
        if "://" in target or target.startswith(("/", "mailto:")):
            continue
        path = posixpath.normpath(posixpath.join(posixpath.dirname(page_uri), target))
        if path.startswith("../") and "." in posixpath.basename(path):
            yield path


def on_files(files, config):
    docs_dir, site_dir = config["docs_dir"], config["site_dir"]
    wanted = set()
    for page in files.documentation_pages():
        with open(page.abs_src_path, encoding="utf-8") as f:
            wanted.update(_outside_targets(page.src_uri, f.read()))
    for path in sorted(wanted):
        if os.path.isfile(os.path.join(docs_dir, path)):
            files.append(RepositoryFile(path, docs_dir, site_dir))
    return files
