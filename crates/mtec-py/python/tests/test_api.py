"""The module as a whole: every function documented with a runnable example, the exception
types, the stubs."""

import doctest
from pathlib import Path

import pytest

import mtec

FUNCTIONS = [n for n in mtec.__all__ if n not in ("InputError", "__version__")]


@pytest.mark.parametrize("name", FUNCTIONS)
def test_docstring_example_runs(name):
    f = getattr(mtec, name)
    tests = doctest.DocTestFinder().find(f, name, globs={})
    examples = sum(len(t.examples) for t in tests)
    assert examples >= 2, f"{name} has no example in its docstring"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for t in tests:
        runner.run(t)
    assert runner.failures == 0, f"{name}: {runner.failures} failing example(s)"


def test_exception_hierarchy():
    assert issubclass(mtec.InputError, ValueError)
    try:
        mtec.iso230_2({"target_mm": [0.0, 1.0, 0.0, 1.0], "run": [1, 1, 1, 1],
                       "direction": ["+", "+", "-", "-"], "deviation_um": [1.0, 2.0, 1.0, 2.0]})
    except mtec.InputError as e:
        assert e.file == "<arrays>" and e.line is None and e.column is None
        assert "at least 2" in e.message and str(e).startswith("<arrays>: ")
    else:
        pytest.fail("one run per direction must be refused")
    with pytest.raises(ValueError) as e:
        mtec.map_fit({"x_mm": [0.0]}, controller="haas")
    assert not isinstance(e.value, mtec.InputError)


def test_stubs_name_every_function():
    pkg = Path(mtec.__file__).parent
    assert (pkg / "py.typed").is_file()
    stubs = (pkg / "__init__.pyi").read_text()
    for name in FUNCTIONS:
        assert f"def {name}(" in stubs, name


def test_docs_examples_run():
    """The examples of docs/python.md run and print what the page says."""
    from conftest import REPO

    text = (REPO / "docs" / "python.md").read_text()
    blocks = [b.split("```", 1)[0] for b in text.split("```python\n")[1:]]
    parser = doctest.DocTestParser()
    test = parser.get_doctest("\n".join(blocks), {}, "docs/python.md", None, 0)
    assert len(test.examples) >= 8
    runner = doctest.DocTestRunner()
    runner.run(test)
    assert runner.failures == 0
