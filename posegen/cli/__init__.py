"""The command line: one module per subcommand, over the stages' public functions.

A command parses its arguments, calls one public function of its stage, renders the
result (text on stdout, a progress bar on stderr) and leaves errors to :func:`main`,
which turns them into exit codes.
"""

from posegen.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
