"""MkDocs hook: ``<!-- kinds: SECTION -->`` in a page becomes that registry's reference,
generated from the code (:func:`twin.kinds_doc.kinds_markdown`)."""

import re

from twin.kinds_doc import kinds_markdown

MARKER = re.compile(r"<!-- kinds: ([a-z]+) -->")


def on_page_markdown(markdown, page, config, files):
    return MARKER.sub(lambda m: kinds_markdown(m.group(1)), markdown)
