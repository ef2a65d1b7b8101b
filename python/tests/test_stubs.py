"""The type stubs (_native.pyi) cover the native module, each entry with a docstring."""

import ast
import inspect
import pathlib

import twinloop
from twinloop import _native

STUB = pathlib.Path(twinloop.__file__).with_name("_native.pyi")


def stub_entries():
    tree = ast.parse(STUB.read_text())
    entries = {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            entries[node.name] = node
            if isinstance(node, ast.ClassDef):
                for member in node.body:
                    if isinstance(member, ast.FunctionDef):
                        entries[f"{node.name}.{member.name}"] = member
    return entries


def test_every_public_name_has_a_stub_with_a_docstring():
    entries = stub_entries()
    missing, undocumented = [], []
    for name, obj in vars(_native).items():
        if name.startswith("_"):
            continue
        names = [name]
        if inspect.isclass(obj) and not issubclass(obj, BaseException):
            names += [f"{name}.{m}" for m in vars(obj) if not m.startswith("_")]
        for n in names:
            if n not in entries:
                missing.append(n)
            elif not ast.get_docstring(entries[n]):
                undocumented.append(n)
    assert not missing, f"not in _native.pyi: {missing}"
    assert not undocumented, f"no docstring in _native.pyi: {undocumented}"


def test_stub_signatures_name_the_native_arguments():
    # The keyword arguments a caller may pass are the ones the stub shows.
    entries = stub_entries()
    for name in ("rnea_batch", "aba_batch", "sysid_arx", "sysid_ss", "tipover_changes", "identify_static"):
        stub_args = [a.arg for a in entries[name].args.args + entries[name].args.kwonlyargs]
        native = list(inspect.signature(getattr(_native, name)).parameters)
        assert stub_args == native, name
