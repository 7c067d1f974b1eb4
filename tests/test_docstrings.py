"""The examples in the compiled module's docstrings run and give what they show."""

import doctest

import pytest

import inexact_loops as il
from inexact_loops import _core

#: The classes and functions (constants such as ``DEFAULT_SAMPLER`` have no docstring of their own).
PUBLIC = [obj for name in _core.__all__ if callable(obj := getattr(_core, name))]


@pytest.mark.parametrize("obj", PUBLIC, ids=lambda obj: obj.__name__)
def test_docstring_examples(obj: object) -> None:
    finder = doctest.DocTestFinder(recurse=True)
    runner = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE)
    tests = finder.find(obj, name=obj.__name__, globs={"il": il})
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0


def test_every_public_item_is_documented() -> None:
    for obj in PUBLIC:
        assert obj.__doc__ and len(obj.__doc__) > 40, obj
    for cls in (il.Trajectory, il.Loops):
        for name in dir(cls):
            if not name.startswith("_"):
                assert getattr(cls, name).__doc__, f"{cls.__name__}.{name}"


def test_examples_are_found() -> None:
    finder = doctest.DocTestFinder(recurse=True)
    found = sum(len(t.examples) for obj in PUBLIC for t in finder.find(obj, name=obj.__name__))
    assert found >= 10, "the compiled docstrings lost their examples"
