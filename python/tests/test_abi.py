"""The binding's view of the C library must match the C library.

Every struct that python/sem/_lib.py mirrors is compared, field by field (name, kind,
array length), with its definition parsed from include/sem/*.h, so adding, removing,
reordering or retyping a field in C fails here instead of shifting the fields Python reads.
And the shared library exports the public API only.
"""
import ctypes
import os
import re

import sem
from sem import _lib

from conftest import SOURCE_DIR

HEADERS = os.path.join(SOURCE_DIR, "include", "sem")


def _headers_text():
    text = ""
    for name in sorted(os.listdir(HEADERS)):
        if name.endswith(".h") or name.endswith(".h.in"):
            with open(os.path.join(HEADERS, name)) as f:
                text += f.read() + "\n"
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


TEXT = _headers_text()
ENUMS = set(re.findall(r"typedef\s+enum\s+\w*\s*\{[^}]*\}\s*(\w+)\s*;", TEXT))
FUNCTION_POINTERS = set(re.findall(r"typedef\s+[\w\s\*]+\(\s*\*\s*(\w+)\s*\)", TEXT))


def c_fields(struct):
    """[(name, kind, length)] of `typedef struct struct {...} struct;` in the headers."""
    m = re.search(r"typedef\s+struct\s+%s\s*\{(.*?)\}\s*%s\s*;" % (struct, struct), TEXT, re.S)
    assert m, "struct %s not found in include/sem" % struct
    fields = []
    for decl in m.group(1).split(";"):
        decl = " ".join(decl.split())
        if not decl:
            continue
        head = re.match(r"((?:const\s+|unsigned\s+|long\s+)*\w+)\s+(.*)", decl)
        base, names = head.group(1), head.group(2)
        base = re.sub(r"\bconst\s+", "", base)
        for name in names.split(","):
            name = name.strip()
            pointer = name.startswith("*")
            name = name.lstrip("* ")
            length = 0
            arr = re.match(r"(\w+)\s*\[\s*(\d+)\s*\]", name)
            if arr:
                name, length = arr.group(1), int(arr.group(2))
            if pointer or base in FUNCTION_POINTERS:
                kind = "pointer"
            elif base in ENUMS or base == "int":
                kind = "int"
            elif base == "unsigned long long":
                kind = "unsigned long long"
            else:
                kind = base  # double, char, or a struct name
            fields.append((name, kind, length))
    return fields


def py_fields(cls):
    out = []
    for name, t in cls._fields_:
        length = 0
        if issubclass(t, ctypes.Array) and t._type_ in (ctypes.c_char, ctypes.c_double,
                                                         ctypes.c_float, ctypes.c_int):
            length, t = t._length_, t._type_
        if t is ctypes.c_int:
            kind = "int"
        elif t is ctypes.c_double:
            kind = "double"
        elif t is ctypes.c_float:
            kind = "float"
        elif t is ctypes.c_char:
            kind = "char"
        elif t is ctypes.c_ulonglong:
            kind = "unsigned long long"
        elif t is ctypes.c_longlong:
            kind = "long long"
        elif t in (ctypes.c_void_p, ctypes.c_char_p) or issubclass(
                t, (ctypes._Pointer, ctypes._CFuncPtr)):
            kind = "pointer"
        elif issubclass(t, ctypes.Structure):
            kind = t.__name__
        else:
            raise AssertionError("unexpected ctypes type %r in %s" % (t, cls.__name__))
        out.append((name, kind, length))
    return out


def test_mirrored_structs_match_the_headers():
    assert len(_lib.MIRRORED_STRUCTS) >= 10
    for cls in _lib.MIRRORED_STRUCTS:
        assert py_fields(cls) == c_fields(cls.__name__), cls.__name__


def test_the_header_parser_sees_a_changed_struct():
    # the check above is only worth something if a difference shows
    fields = c_fields("sem_object_stats")
    assert fields[0] == ("volume", "double", 0)
    assert ("center_of_mass", "double", 3) in fields
    assert py_fields(_lib.sem_object_stats)[:-1] != fields


def test_only_the_public_api_is_exported():
    lib = _lib.lib
    for name in _lib._PROTOTYPES:
        assert hasattr(lib, name), name
    # internal helpers with the sem_ prefix stay inside libsem.so (version script)
    for internal in ("sem_atomic_open", "sem_linear_solver_name", "sem_bench_is_dir"):
        assert not hasattr(lib, internal), internal


def test_version():
    assert re.fullmatch(r"\d+\.\d+\.\d+", sem.version())
    with open(os.path.join(HEADERS, "version.h.in")) as f:
        assert "sem_version(void)" in f.read()
