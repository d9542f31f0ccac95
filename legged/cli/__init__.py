"""The `legged` command line: argument parsing, dispatch and printing, the top layer (free to import everything;
nothing else in `legged` imports it).

main: the parser, the dispatch and the commands without another home; args: argument types and shared options;
nav, soccer, runs, bench: the commands of each group; demo: `legged demo`; reference: the generated reference
page, docs/cli-reference.md. The work itself lives in the libraries (legged, planners, policies, web), which each
command imports when it runs: `legged --help` and a wrong argument answer before torch, Brax and the task
registry load."""

from legged.cli.main import main

__all__ = ["main"]
