"""Argument types of the `legged` command line: every number has a range and every name is checked, so
that a mistyped or absurd value fails at once with one line naming it."""

from __future__ import annotations

import argparse


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors: `legged <command>: error: <cause>` on stderr, exit code 2 (no usage
    dump; `legged <command> --help` shows it)."""

    def error(self, message: str):
        """Print `message` as one line and exit with code 2."""
        self.exit(2, f"{self.prog}: error: {message}\n")


def ints(minimum: int, maximum: int = 10**9):
    """Parser of comma-separated integers in [minimum, maximum] (for argparse `type=`)."""

    def parse(text: str) -> list[int]:
        try:
            values = [int(v) for v in text.split(",") if v.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None
        if not values or min(values) < minimum or max(values) > maximum:
            raise argparse.ArgumentTypeError(f"expected comma-separated integers from {minimum} to {maximum:,}, "
                                             f"got {text!r}")
        return values

    return parse


def choices(*allowed: str):
    """Parser of a comma-separated subset of `allowed` names (for argparse `type=`)."""

    def parse(text: str) -> list[str]:
        values = [v.strip() for v in text.split(",") if v.strip()]
        unknown = [v for v in values if v not in allowed]
        if not values or unknown:
            raise argparse.ArgumentTypeError(f"choose from {', '.join(allowed)} (comma-separated), got {text!r}")
        return values

    return parse


def task_names(text: str) -> list[str]:
    """Comma-separated registered task names (for argparse `type=`)."""
    from legged.tasks import TASKS

    names = [t.strip() for t in text.split(",") if t.strip()]
    unknown = [t for t in names if t not in TASKS]
    if not names or unknown:
        raise argparse.ArgumentTypeError(f"unknown task(s) {unknown or text!r}; known: {', '.join(sorted(TASKS))}")
    return names


def bounded(kind: type, lo: float, hi: float):
    """Parser of one number: a whole number in [lo, hi] (kind=int) or a finite one in (lo, hi] (kind=float)."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {'a whole number' if kind is int else 'a number'}, "
                                             f"got {text!r}") from None
        if kind is int and not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be between {lo:,} and {hi:,}, got {value:,}")
        if kind is not int and not lo < value <= hi:  # NaN fails here too
            raise argparse.ArgumentTypeError(f"must be greater than {lo:g} and at most {hi:g}, got {text}")
        return value

    return parse


SEED = bounded(int, 0, 2**31 - 1)
"""A seed."""
THREADS = bounded(int, 1, 1024)
"""A thread count."""


def xyz(text: str) -> list[float]:
    """Parser of a body position X,Y,Z in metres."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z in metres, got {text!r}") from None
    if len(values) != 3 or not all(abs(v) < 1e6 for v in values):  # NaN fails here too
        raise argparse.ArgumentTypeError(f"expected three finite comma-separated numbers X,Y,Z, got {text!r}")
    return values


def join_negative_coordinates(argv: list[str]) -> list[str]:
    """Let `--start -2,0,0.27` work: argparse would read '-2,0,0.27' as an option."""
    out = []
    for token in argv:
        if out and out[-1] in ("--start", "--goal") and token[:1] == "-" and token[1:2].isdigit():
            out[-1] = f"{out[-1]}={token}"
        else:
            out.append(token)
    return out


def add_robot_option(parser) -> None:
    """--robot: the robot model a policy runs on."""
    parser.add_argument("--robot", default="project", metavar="project|menagerie|playground|PATH.xml",
                        help="the robot model the policy runs on: the project's (default), MuJoCo Menagerie's, MuJoCo "
                             "Playground's (Go1) or an MJCF file of the same robot; actuators are set to the policy's")


def add_physics_options(parser, default: str = "mjx") -> None:
    """--physics and --threads."""
    parser.add_argument("--physics", choices=["mjx", "native"], default=default,
                        help="physics engine: mjx (JAX; for accelerators) or native (MuJoCo's C engine; fastest on "
                             "a CPU)")
    parser.add_argument("--threads", type=THREADS, default=0, metavar="N",
                        help="CPU threads of native physics and torch (default: every core)")


def add_server_options(parser, port: int = 8080) -> None:
    """--host and --port of the dashboard's server."""
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to bind (default 127.0.0.1, this machine only; 0.0.0.0 exposes it)")
    parser.add_argument("--port", type=bounded(int, 0, 65535), default=port, help="port to bind (0: any free port)")
