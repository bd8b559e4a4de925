"""Test oracles: generators of perturbed, random and malformed grasp states and documents.

Used by the tests and by ``tools/`` (which put the repository root on ``sys.path``), never by
the runtime package: :mod:`tests.support.perturb` (states changed in one controlled way),
:mod:`tests.support.fuzz` (mutated ``mjtvm.state/1`` and ``mjtvm.grasp/1`` documents) and
:mod:`tests.support.documents` (grasp files and scenarios written as TOML and JSON).
"""
