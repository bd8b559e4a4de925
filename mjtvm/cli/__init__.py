r"""The ``mjtvm`` command line: thin wrappers over the library (the options: ``docs/cli.md``).

Exit codes
----------
0
    Success (also ``--help`` and ``--version``).
1
    Another failure the package reports (e.g. a rerun recording that fails).
2
    Bad input, printed as one line ``error: <what>: <expected>`` on stderr: a malformed or
    out-of-range option (the ranges: :mod:`~mjtvm.cli.values`; argparse's errors too, followed
    by ``(try 'mjtvm CMD --help')``), options that together exceed a bound
    (:class:`~mjtvm.errors.OptionError`), an
    invalid state file (:class:`~mjtvm.errors.StateError`) or scenario
    (:class:`~mjtvm.errors.ModelError`), an output folder that cannot be written or is in use
    by another run (:class:`~mjtvm.errors.OutputError`, checked before any work), an
    unreachable ``--cluster`` or one that is not a Dask scheduler, an argument the library
    refuses (:class:`~mjtvm.errors.ParamError`).
3
    Solver trouble (:class:`~mjtvm.errors.SolverError`): ``solver error: ...``.
130
    Interrupted (Ctrl-C, SIGINT): one line ``mjtvm: interrupted``, no traceback; output
    files are either untouched or complete (``sweep`` keeps a checkpoint of its finished rows).
141
    Standard output closed early (``mjtvm solve | head -c 10``): nothing more is printed.

Modules: :mod:`~mjtvm.cli.parser` (the parser, :func:`main`), :mod:`~mjtvm.cli.solve`
(``solve``, ``export-state``, ``tvms``), :mod:`~mjtvm.cli.lift` (``replay``, ``sweep``),
:mod:`~mjtvm.cli.verify`, :mod:`~mjtvm.cli.bench`, :mod:`~mjtvm.cli.options` (parser, removed
spellings, shared options), :mod:`~mjtvm.cli.values` (option types), :mod:`~mjtvm.cli.output`
(exit codes, standard output).
"""

from __future__ import annotations

from .output import emit
from .parser import build_parser, main
from .solve import example_path
from .verify import verify_parser

__all__ = ["build_parser", "emit", "example_path", "main", "verify_parser"]
