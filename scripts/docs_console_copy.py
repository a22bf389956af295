"""mkdocs hook: the copy button of a console block copies its commands only, without the
`$ ` prompts and without what the commands print, so that a reader can paste a step into a
shell as it is. A command continued on the next line with a trailing backslash stays one
command. The theme copies an element's `data-copy` text where it has one."""

import html
import re

from mkdocs.config.defaults import MkDocsConfig
from mkdocs.structure.files import Files
from mkdocs.structure.pages import Page

# A highlighted block: the prompts are Pygments' "generic prompt" spans.
_BLOCK = re.compile(r"<code>(?P<body>(?:(?!</code>).)*?<span class=\"gp\">.*?)</code>",
                    re.DOTALL)
_TAG = re.compile(r"<[^>]+>")


def commands(block_text: str) -> str:
    """The commands of a console block's text: each `$ ` line and the lines a trailing
    backslash continues it onto."""
    found: list[str] = []
    continued = False
    for line in block_text.splitlines():
        if line.startswith("$ ") or continued:
            found.append(line[2:] if line.startswith("$ ") and not continued else line)
            continued = line.rstrip().endswith("\\")
    return "\n".join(found)


def with_copy_text(page_html: str) -> str:
    """The page with each console block's code carrying its commands as `data-copy`."""
    def annotate(match: re.Match[str]) -> str:
        text = html.unescape(_TAG.sub("", match.group("body")))
        copied = html.escape(commands(text), quote=True)
        return f'<code data-copy="{copied}">{match.group("body")}</code>'

    return _BLOCK.sub(annotate, page_html)


def on_page_content(html_text: str, page: Page, config: MkDocsConfig, files: Files) -> str:
    return with_copy_text(html_text)
