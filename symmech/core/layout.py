"""Declared layouts: an engine's parameter, state and output vectors written once, as data.

A compiled engine passes its data in float64 vectors whose slots both sides must agree on. A
:class:`Layout` declares such a vector as a sequence of :class:`Field` (name, unit, meaning, shape); the
offsets, ``pack``/``unpack``, the loop's constants (:attr:`Layout.slots`, a named tuple of offsets that
numba reads as compile-time integers), the labels and the numba argument types all come from it. A
:class:`Bundle` declares a tuple of arrays the same way (the elastic trolley's model): its fields carry a
dtype and named dimensions, it packs into a named tuple that numba types field by field.

The declarations are what the export to C structs and FMU variables reads: names, units, meanings, offsets
and shapes. Nothing here imports numba at import time (the grain engine's Python side runs without it).
"""
from __future__ import annotations

import dataclasses
import functools
import math
from collections import namedtuple
from dataclasses import dataclass
from functools import cached_property

import numpy as np


@dataclass(frozen=True)
class Field:
    """One named entry of a layout.

    name     a Python identifier, unique in its layout
    unit     SI unit ("1" for a pure number or a code, "" for an index or a count)
    meaning  one line
    shape    () for a scalar; ints or dimension names for a slot vector (:class:`Layout`: a name is a size
             given when the model is built, :meth:`Layout.sized`) or an array of a :class:`Bundle`
    dtype    numpy dtype name of the values (a :class:`Layout` holds float64 only)
    """

    name: str
    unit: str
    meaning: str
    shape: tuple = ()
    dtype: str = "float64"

    @property
    def size(self) -> int:
        """Number of slots the field takes in a :class:`Layout` (1 for a scalar)."""
        return math.prod(self.shape)

    @property
    def open(self) -> tuple:
        """The dimension names of its shape, in order (() for a fixed shape)."""
        return tuple(d for d in self.shape if isinstance(d, str))


def _check_names(fields: tuple, what: str) -> None:
    names = [f.name for f in fields]
    bad = [n for n in names if not n.isidentifier() or n.startswith("_")]
    if bad or len(set(names)) != len(names):
        raise ValueError(f"{what}: field names must be unique public identifiers, got {names}")


class _Declared:
    """What a layout and a bundle share: their ``fields``' names and units, in order."""

    @property
    def names(self) -> tuple:
        """The field names, in order."""
        return tuple(f.name for f in self.fields)

    @property
    def units(self) -> tuple:
        """The field units, in order."""
        return tuple(f.unit for f in self.fields)


@dataclass(frozen=True)
class Layout(_Declared):
    """A float64 vector of named fields at consecutive offsets, in declaration order.

    ``name`` is a Python identifier: the name of the offsets' named tuple (:attr:`slots`) and of a C struct.
    A field's shape may name a dimension (``("N",)``: a model's N coordinates): such a layout is a family, and
    :meth:`sized` gives the member of a model; its compiled readers take that member's :meth:`edges` at run time
    and index them with the constant :attr:`positions`.
    """

    name: str
    fields: tuple

    def __post_init__(self):
        _check_names(self.fields, self.name)
        if any(f.dtype != "float64" or not all(isinstance(d, (int, str)) for d in f.shape) for f in self.fields):
            raise ValueError(f"{self.name}: a layout holds float64 fields of integer or named shapes")

    @property
    def dims(self) -> tuple:
        """The dimension names its fields leave open, in order of first use (() for a fixed size)."""
        return tuple(dict.fromkeys(d for f in self.fields for d in f.open))

    def sized(self, **dims: int) -> Layout:
        """This layout with every open dimension given (``STATE.sized(N=7)``): a layout of fixed size, the same
        name and fields (cached per sizes); ValueError for a missing, unknown or negative size."""
        if set(dims) != set(self.dims) or any(not isinstance(v, int) or v < 0 for v in dims.values()):
            raise ValueError(f"{self.name}.sized: sizes of {self.dims} expected (ints >= 0), got {dims}")
        return _sized(self, tuple(sorted(dims.items())))

    @cached_property
    def _edges(self) -> list:
        if self.dims:
            raise ValueError(f"{self.name}: the sizes of {self.dims} are open; {self.name}.sized(...) gives them")
        return np.cumsum([0] + [f.size for f in self.fields]).tolist()

    @cached_property
    def _offsets(self) -> dict:
        return dict(zip(self.names, self._edges))

    @property
    def size(self) -> int:
        """Length of the vector."""
        return self._edges[-1]

    @cached_property
    def positions(self) -> tuple:
        """The fields' positions in declaration order as a named tuple (``positions.q``): constants a compiled
        loop indexes :meth:`edges` with (``at[Q.qd]`` is where the field qd starts, ``at[Q.qd + 1]`` where it
        ends), the same for every member of a family of layouts."""
        return namedtuple(f"{self.name}Fields", self.names)(*range(len(self.fields)))

    def edges(self) -> np.ndarray:
        """Where each field starts, then the vector's length (len(fields) + 1,) int64: the offsets a compiled
        loop reads at run time when they depend on the model's sizes (a record's array)."""
        return np.array(self._edges, dtype=np.int64)

    def field(self, name: str) -> Field:
        """The field called ``name`` (KeyError naming the layout otherwise)."""
        for f in self.fields:
            if f.name == name:
                return f
        raise KeyError(f"{self.name} has no field {name!r}; fields: {', '.join(self.names)}")

    def offset(self, name: str) -> int:
        """Index of the first slot of field ``name``."""
        self.field(name)
        return self._offsets[name]

    def slice(self, name: str) -> slice:
        """The slots of field ``name``."""
        start = self.offset(name)
        return slice(start, start + self.field(name).size)

    @cached_property
    def slots(self) -> tuple:
        """The offsets as a named tuple (``slots.mass``): a module-level constant that numba freezes into the
        compiled code, so a loop reads ``p[P_AT.mass]`` as it would read ``p[3]``."""
        return namedtuple(self.name, self.names)(**self._offsets)

    @property
    def labels(self) -> tuple:
        """One label per slot: the field name, with the flat index for a field of several slots
        (``axes[0]``); column names of a table, variable names of an export."""
        return tuple(f.name if f.shape == () else f"{f.name}[{k}]" for f in self.fields for k in range(f.size))

    @cached_property
    def pack(self):
        """``pack(**values)`` -> the vector (size,) from every field's value by name (a scalar, or an array of
        the field's shape); a missing or unknown name is a TypeError, a value of the wrong shape a ValueError
        naming the field. Written out for this layout once (``array([*axes, mass, ...], float)`` after a length
        check of every vector field): ~3 us for 23 fields, a loop over the fields ~10 (a short grain run takes
        0.2 ms)."""
        def flat(f: Field) -> str:
            return f.name if f.shape == () else f"*{f.name}" if len(f.shape) == 1 else f"*ravel({f.name})"

        checks = " or ".join(f"len({f.name}) != {f.size}" if len(f.shape) == 1 else f"shape({f.name}) != {f.shape}"
                             for f in self.fields if f.shape) or "False"
        every = ", ".join(f"{n}={n}" for n in self.names)
        source = (f"def pack(*, {', '.join(self.names)}):\n"
                  f"    if {checks}:\n        fail({every})\n"
                  f"    try:\n        return array([{', '.join(flat(f) for f in self.fields)}], float)\n"
                  f"    except (TypeError, ValueError):\n        fail({every})\n")
        namespace = {"array": np.array, "ravel": np.ravel, "shape": np.shape, "fail": self._refuse}
        exec(source, namespace)  # the names are identifiers (checked in __post_init__)
        return namespace["pack"]

    def _refuse(self, **values):
        """The ValueError of a pack whose values do not fit the fields."""
        bad = [f"{f.name} has shape {np.shape(values[f.name])}, expected {f.shape}" for f in self.fields
               if np.shape(values[f.name]) != f.shape]
        raise ValueError(f"{self.name}.pack: {'; '.join(bad) or 'a value is not a number'}")

    @cached_property
    def _where(self) -> tuple:
        return tuple((f.name, self.offset(f.name) if f.shape == () else self.slice(f.name), f.shape)
                     for f in self.fields)

    def unpack(self, vec) -> dict:
        """{name: value} of the vector ``vec`` (size,): a float for a scalar field, else a view of vec of the
        field's shape."""
        if np.shape(vec) != (self.size,):
            raise ValueError(f"{self.name}.unpack: a vector of shape ({self.size},) expected, got {np.shape(vec)}")
        return {name: float(vec[at]) if shape == () else vec[at] if len(shape) == 1 else vec[at].reshape(shape)
                for name, at, shape in self._where}

    def split(self, array) -> dict:
        """{name: view} of ``array`` (..., size) along its last axis: each field's slots (..., field size), for
        arrays whose last axis this layout declares (a generated function's output columns, a table's rows)."""
        if np.shape(array)[-1:] != (self.size,):
            raise ValueError(f"{self.name}.split: a last axis of {self.size} expected, got shape {np.shape(array)}")
        return {f.name: array[..., self.slice(f.name)] for f in self.fields}

    def zeros(self) -> np.ndarray:
        """A vector of zeros (size,)."""
        return np.zeros(self.size)

    def numba_type(self):
        """The numba type of the vector as an engine takes it: a C-contiguous 1-d float64 array."""
        from numba import types

        return types.Array(types.float64, 1, "C")


@functools.lru_cache(maxsize=64)
def _sized(layout: Layout, dims: tuple) -> Layout:
    """The member of a family of layouts at the sizes ``dims`` ((name, size) pairs)."""
    given = dict(dims)
    return Layout(layout.name, tuple(dataclasses.replace(f, shape=tuple(given.get(d, d) for d in f.shape))
                                     for f in layout.fields))


@dataclass(frozen=True)
class Bundle(_Declared):
    """A tuple of arrays of named fields, in declaration order: a model handed to compiled kernels whole.

    ``name`` is the name of its named tuple class, which ``module`` (the declaring module) must bind under
    that name (numba's cache pickles the class by reference): ``Model = MODEL.record`` in module ``module``.
    """

    name: str
    module: str
    fields: tuple

    def __post_init__(self):
        _check_names(self.fields, self.name)

    @cached_property
    def record(self) -> type:
        """The named tuple class the kernels take (``mdl.ptr``: numba resolves the attribute when typing)."""
        return namedtuple(self.name, self.names, module=self.module)

    def pack(self, **arrays):
        """The record from every field's array by name, each converted to its dtype, C-contiguous, and checked
        for its number of dimensions."""
        missing, extra = set(self.names) - set(arrays), set(arrays) - set(self.names)
        if missing or extra:
            raise ValueError(f"{self.name}.pack: missing {sorted(missing)}, unknown {sorted(extra)}")
        values = {}
        for f in self.fields:
            value = np.ascontiguousarray(arrays[f.name], dtype=f.dtype)
            if value.ndim != len(f.shape):
                raise ValueError(f"{self.name}.pack: {f.name} has {value.ndim} dimensions, expected "
                                 f"{len(f.shape)} {f.shape}")
            values[f.name] = value
        return self.record(**values)

    def unpack(self, record) -> dict:
        """{name: array} of a record."""
        return dict(zip(self.names, record))

    def numba_type(self):
        """The numba type of the record: a named tuple of C-contiguous arrays of the fields' dtypes and
        dimensions."""
        from numba import from_dtype, types

        arrays = [types.Array(from_dtype(np.dtype(f.dtype)), len(f.shape), "C") for f in self.fields]
        return types.BaseTuple.from_types(arrays, self.record)
