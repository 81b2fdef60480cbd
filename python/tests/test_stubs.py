"""The type stubs name what the native module has, and every public thing has a docstring."""

import ast
import inspect
from pathlib import Path

import presrs
from presrs import _native

STUBS = Path(presrs.__file__).with_name("_native.pyi")


def _stubbed():
    tree = ast.parse(STUBS.read_text())
    names, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        if isinstance(node, ast.AnnAssign) and not node.target.id.startswith("_"):
            names.add(node.target.id)  # module constants, e.g. CLASSIFIERS: tuple[str, ...]
        if isinstance(node, ast.ClassDef):
            members[node.name] = {
                n.name if isinstance(n, ast.FunctionDef) else n.target.id
                for n in node.body
                if isinstance(n, ast.FunctionDef) or isinstance(n, ast.AnnAssign)
            }
    return names, members


def test_stubs_match_the_native_module():
    names, members = _stubbed()
    public = {n for n in dir(_native) if not n.startswith("_")}
    assert names == public
    for cls, stubbed in members.items():
        actual = {n for n in dir(getattr(_native, cls)) if not n.startswith("_")}
        assert stubbed - {"__init__", "__len__"} == actual, cls


def test_everything_public_has_a_docstring():
    missing = []
    for name in presrs.__all__:
        obj = getattr(presrs, name)
        if inspect.isclass(obj) or callable(obj):
            if not (obj.__doc__ or "").strip():
                missing.append(name)
            if inspect.isclass(obj):
                for member, value in vars(obj).items():
                    if not member.startswith("_") and not (getattr(value, "__doc__", "") or "").strip():
                        missing.append(f"{name}.{member}")
    assert not missing, missing


def test_the_registered_names_are_exported():
    # The classifier and feature-family names come from the library's registration.
    assert presrs.CLASSIFIERS[:5] == ("pwe", "mle", "lda", "svm", "knn")
    assert {"fft1d", "fft2d", "fft2d_polar", "glcm", "contact"} <= set(presrs.FEATURE_FAMILIES)
