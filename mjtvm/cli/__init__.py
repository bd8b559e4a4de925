r"""The ``mjtvm`` command line: thin wrappers over the library (the options: ``docs/cli.md``).

Exit codes
----------
0
    Success (also ``--help`` and ``--version``).
1
    Another failure the package reports (e.g. a rerun recording that fails).
2
    Bad input, printed as one line ``error: <what>: <expected>`` on stderr: a malformed or
    out-of-range option (the ranges: [`values`][mjtvm.cli.values]; argparse's errors too, followed
    by ``(try 'mjtvm CMD --help')``), options that together exceed a bound
    ([`OptionError`][mjtvm.errors.OptionError]), an
    invalid state file ([`StateError`][mjtvm.errors.StateError]) or scenario
    ([`ModelError`][mjtvm.errors.ModelError]), an output folder that cannot be written or is in use
    by another run ([`OutputError`][mjtvm.errors.OutputError], checked before any work), an
    unreachable ``--cluster`` or one that is not a Dask scheduler, an argument the library
    refuses ([`ParamError`][mjtvm.errors.ParamError]).
3
    Solver trouble ([`SolverError`][mjtvm.errors.SolverError]): ``solver error: ...``.
130
    Interrupted (Ctrl-C, SIGINT): one line ``mjtvm: interrupted``, no traceback; output
    files are either untouched or complete (``sweep`` keeps a checkpoint of its finished rows).
141
    Standard output closed early (``mjtvm solve | head -c 10``): nothing more is printed.

Modules: [`parser`][mjtvm.cli.parser] (the parser, [`main()`][mjtvm.cli.parser.main]), [`solve`][mjtvm.cli.solve]
(``solve``, ``export-state``, ``tvms``), [`lift`][mjtvm.cli.lift] (``replay``, ``sweep``),
[`verify`][mjtvm.cli.verify], [`options`][mjtvm.cli.options] (parser, removed
spellings, shared options), [`values`][mjtvm.cli.values] (option types), [`output`][mjtvm.cli.output]
(exit codes, standard output).
"""

from __future__ import annotations

from mjtvm.cli.parser import build_parser, guarded, main
from mjtvm.cli.solve import example_path
from mjtvm.cli.verify import verify_parser

__all__ = ["build_parser", "example_path", "guarded", "main", "verify_parser"]
