"""The command-line reference page, docs/cli-reference.md, generated from the parser (`build_parser`): every
command and subcommand with its usage line and its options with their help texts. Regenerate it after changing
an option with `python -m legged.cli.reference` (tests/test_docs.py fails while the committed page differs)."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from legged.cli.main import build_parser

PAGE = Path(__file__).resolve().parents[2] / "docs" / "cli-reference.md"
"""The committed page."""
USAGE_WIDTH = 100
"""Columns of the usage lines: fixed, so that the page does not depend on the terminal that writes it."""
TEXT_WIDTH = 116
"""Columns of the page's running text."""

HEADER = """\
# Command-line reference

Every command of `legged` and its options, generated from the parser by `python -m legged.cli.reference`
(legged/cli/reference.py): do not edit this page by hand; tests/test_docs.py fails when it differs from the
parser. The guide with examples and what each command prints: [The command line](cli.md).
"""

_CODE_SPAN = re.compile(r"(`[^`]*`)")
_LIST_OR_HEADING = re.compile(r"^([-*+]|\d+[.)]|#+)(\s|$)")


def _escape(text: str) -> str:
    """Help text as Markdown: code spans (`...`) kept, elsewhere `*`, `<`, `[` and `]` escaped, so that `RRT*` or
    `<term>` print as they read."""
    parts = _CODE_SPAN.split(text)
    for i in range(0, len(parts), 2):  # the text between code spans
        parts[i] = (parts[i].replace("\\", "\\\\").replace("*", "\\*").replace("<", "&lt;")
                    .replace("[", "\\[").replace("]", "\\]"))
    return "".join(parts)


def _wrap(text: str, indent: str = "") -> list[str]:
    """`text` as lines of at most TEXT_WIDTH columns (a long word alone may exceed it), continuation lines indented
    by `indent`, never broken inside a code span nor so that a line reads as a list item or a heading."""
    words = re.findall(r"`[^`]*`\S*|\S+", text)
    lines, line = [], ""
    for word in words:
        if line and len(line) + 1 + len(word) > TEXT_WIDTH and not _LIST_OR_HEADING.match(word + " "):
            lines.append(line)
            line = indent + word
        else:
            line = f"{line} {word}" if line else word
    return lines + [line] if line else lines


def _usage(parser: argparse.ArgumentParser) -> str:
    """The parser's usage line(s), wrapped at USAGE_WIDTH columns."""
    formatter = argparse.HelpFormatter(prog=parser.prog, width=USAGE_WIDTH)
    formatter.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups)
    return formatter.format_help().strip()


def _invocation(action: argparse.Action, parser: argparse.ArgumentParser) -> str:
    """How an argument is written: `task`, `--num-envs NUM_ENVS`, `-h, --help`, `--backend {rsl,brax}`."""
    formatter = argparse.HelpFormatter(prog=parser.prog, width=USAGE_WIDTH)
    return formatter._format_action_invocation(action)


def _default(action: argparse.Action) -> str | None:
    """The default worth printing (None: no value, a flag, or one the help text already gives)."""
    value = action.default
    if value is None or value is argparse.SUPPRESS or isinstance(value, bool) or action.nargs == 0:
        return None
    if value == [] or value == "":
        return None
    if isinstance(value, list):
        value = ",".join(str(v) for v in value)
    text = str(value)
    return None if "default" in (action.help or "") else text


def _argument(action: argparse.Action, parser: argparse.ArgumentParser) -> list[str]:
    """One argument as a list item: its invocation, help text, default and whether it is required."""
    formatter = argparse.HelpFormatter(prog=parser.prog, width=USAGE_WIDTH)
    help_text = formatter._expand_help(action) if action.help else ""
    notes = []
    if action.option_strings and action.required:
        notes.append("required")
    default = _default(action)
    if default is not None:
        notes.append(f"default `{default}`")
    text = f"- `{_invocation(action, parser)}`"
    if help_text:
        text += ": " + _escape(" ".join(help_text.split()))
    if notes:
        text += f" ({'; '.join(notes)})"
    return _wrap(text, indent="  ")


def _subcommands(parser: argparse.ArgumentParser) -> list[tuple[str, str, argparse.ArgumentParser]]:
    """(name, help, parser) of each subcommand of `parser`, in the order they were added."""
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help or "" for choice in action._choices_actions}
            seen = set()
            for name, sub in action.choices.items():
                if id(sub) not in seen:  # an alias names the same parser again
                    seen.add(id(sub))
                    found.append((name, helps.get(name, ""), sub))
    return found


def _section(parser: argparse.ArgumentParser, help_text: str, level: int) -> list[str]:
    """A command's section: heading, what it does, usage, arguments, then its subcommands' sections."""
    lines = ["", f"{'#' * level} {parser.prog}", ""]
    about = parser.description or help_text
    if about:
        lines += _wrap(_escape(" ".join(about.split()))) + [""]
    lines += ["```text", _usage(parser), "```"]
    arguments = [a for a in parser._actions
                 if not isinstance(a, (argparse._HelpAction, argparse._SubParsersAction))]
    if arguments:
        lines.append("")
        for action in arguments:
            lines += _argument(action, parser)
    subcommands = _subcommands(parser)
    if subcommands and level > 1:
        links = ", ".join(f"[{name}](#{_anchor(sub.prog)})" for name, _, sub in subcommands)
        lines += [""] + _wrap(f"Subcommands: {links}.")
    for _, sub_help, sub in subcommands:
        lines += _section(sub, sub_help, min(level + 1, 3))
    return lines


def _anchor(heading: str) -> str:
    """The id MkDocs (and GitHub) give a heading of lower-case words and hyphens: `legged bench env` ->
    `legged-bench-env`."""
    return re.sub(r"[^a-z0-9_ -]", "", heading.lower()).replace(" ", "-")


def reference_markdown(parser: argparse.ArgumentParser | None = None) -> str:
    """The page's text for `parser` (default: the `legged` command's)."""
    parser = parser or build_parser()
    commands = _subcommands(parser)
    lines = HEADER.splitlines() + ["", "## Commands", ""]
    for name, help_text, sub in commands:
        lines += _wrap(f"- [{name}](#{_anchor(sub.prog)}): {_escape(' '.join(help_text.split()))}", indent="  ")
    lines += ["", "Every command takes `-h`/`--help`; bad input is one line on stderr and exit code 2."]
    for name, help_text, sub in commands:
        lines += _section(sub, help_text, 2)
    return "\n".join(lines).rstrip() + "\n"


def write_reference(path: str | Path = PAGE) -> Path:
    """Write the page to `path` (default: docs/cli-reference.md) and return the path."""
    path = Path(path)
    path.write_text(reference_markdown(), encoding="utf-8")
    return path


def main(argv: list[str] | None = None) -> int:
    """`python -m legged.cli.reference [PATH]`: write the page (default: docs/cli-reference.md)."""
    argv = sys.argv[1:] if argv is None else argv
    print(f"[reference] wrote {write_reference(*argv[:1])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
