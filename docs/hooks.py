"""MkDocs hook: ``<!-- kinds: SECTION -->`` in a page becomes that registry's reference, and
``<!-- table: NAME -->`` that library's table (the materials), generated from the code
(:func:`twin.kinds_doc.kinds_markdown`, :func:`twin.kinds_doc.table_markdown`)."""

import re

from twin.kinds_doc import kinds_markdown, table_markdown

MARKER = re.compile(r"<!-- kinds: ([a-z]+) -->")
TABLE = re.compile(r"<!-- table: ([a-z]+) -->")


def on_page_markdown(markdown, page, config, files):
    markdown = MARKER.sub(lambda m: kinds_markdown(m.group(1)), markdown)
    return TABLE.sub(lambda m: table_markdown(m.group(1)), markdown)
