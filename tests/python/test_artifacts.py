"""`pip install .` and the C library the README links against do not share a file: the
extension module (also `libvrpn.so`, but needing Python symbols) is built with the cargo
profile `python` into target/python/, away from target/release/."""

import re

import pytest

from conftest import ROOT


def test_the_python_build_leaves_the_c_library_folder_alone():
    readme = (ROOT / "README.md").read_text()
    m = re.search(r"cc -Iinclude \S+ -L(\S+) -lvrpn", readme)
    assert m, "the README's C link command"
    c_dir = (ROOT / m.group(1)).resolve()
    built = [p for p in (ROOT / "target").glob("*/libvrpn.so") if b"PyInit__vrpn" in p.read_bytes()]
    if not built:
        pytest.skip("the module was not built from this checkout")
    for ext in built:
        assert ext.parent.resolve() != c_dir, (
            f"{ext} is the Python extension, where the README tells C programs to find the C library"
        )
    assert any(p.parent.name == "python" for p in built), built
