"""The package itself: its exceptions and its type stubs, which must describe the extension."""

import ast
import inspect
from pathlib import Path

import hystcomp
from hystcomp import _hystcomp

STUB = Path(hystcomp.__file__).with_name("_hystcomp.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    functions, classes, constants = set(), {}, set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            functions.add(node.name)
        elif isinstance(node, ast.ClassDef):
            classes[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.AnnAssign):
            constants.add(node.target.id)
    return functions, classes, constants


def test_stubs_describe_every_public_name_of_the_extension():
    functions, classes, constants = stub_names()
    public = {n for n in dir(_hystcomp) if not n.startswith("_")} | {"__version__"}
    runtime_classes = {n for n in public if inspect.isclass(getattr(_hystcomp, n))}
    runtime_functions = {n for n in public if callable(getattr(_hystcomp, n))} - runtime_classes
    assert runtime_classes == set(classes)
    assert runtime_functions == functions
    assert public - runtime_classes - runtime_functions == constants
    for name, members in classes.items():
        cls = getattr(_hystcomp, name)
        runtime = {m for m in vars(cls) if not m.startswith("_") or m in ("__len__", "__copy__", "__iter__")}
        stubbed = {m for m in members if m != "__init__"}
        assert runtime == stubbed, f"{name}: runtime {sorted(runtime ^ stubbed)} differ from the stub"


def test_every_public_object_has_a_docstring():
    for name in hystcomp.__all__:
        obj = getattr(hystcomp, name)
        if callable(obj):
            assert (obj.__doc__ or "").strip(), f"{name} has no docstring"


def test_exception_hierarchy():
    for name in ("InvalidValueError", "NotInvertibleError", "UnstableDelayError", "WrongDirectionError", "ModelFileError", "IdentificationError", "StageConfigError"):
        cls = getattr(hystcomp, name)
        assert issubclass(cls, hystcomp.HystcompError) and issubclass(cls, ValueError), name
        assert cls.__module__ == "hystcomp"
    assert issubclass(hystcomp.NotInvertibleError, hystcomp.InvalidValueError)
    assert issubclass(hystcomp.UnstableDelayError, hystcomp.NotInvertibleError)
    assert hystcomp.__version__.count(".") == 2


def test_every_public_member_of_the_extension_has_a_docstring():
    missing = []
    for name in dir(_hystcomp):
        cls = getattr(_hystcomp, name)
        if name.startswith("_") or not inspect.isclass(cls) or issubclass(cls, BaseException):
            continue
        for member, value in vars(cls).items():
            if member.startswith("_") and member not in ("__len__", "__copy__"):
                continue
            if not (getattr(value, "__doc__", None) or "").strip():
                missing.append(f"{name}.{member}")
    assert not missing, f"no docstring: {missing}"


def test_every_public_function_of_the_extension_and_package_has_a_docstring():
    functions = {}
    for module in (_hystcomp, hystcomp):
        for name in dir(module):
            obj = getattr(module, name)
            if name.startswith("_") or inspect.isclass(obj) or not callable(obj):
                continue
            functions[f"{module.__name__}.{name}"] = obj
    # The walk found the module-level functions (so this test checks something).
    for expected in ("identify", "e_m", "e_rms", "e_mhe", "tracking_indices", "reproduce", "paper_trajectory"):
        assert f"{_hystcomp.__name__}.{expected}" in functions, expected
        assert f"hystcomp.{expected}" in functions, expected
    missing = [name for name, obj in functions.items() if not (obj.__doc__ or "").strip()]
    assert not missing, f"no docstring: {missing}"


def test_the_stubs_carry_the_extensions_docstrings():
    """Editors show the stub: its docstrings are the extension's (tools/stub_docs.py)."""
    import subprocess
    import sys
    from pathlib import Path

    tool = Path(__file__).resolve().parents[1] / "tools" / "stub_docs.py"
    result = subprocess.run([sys.executable, str(tool), "--check"], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
