"""``symmech export``: generated models that leave Python (layer 5, runtime).

* :mod:`symmech.export.model` turns a scene into an :class:`~symmech.export.model.ExportModel`: the scene's
  generated C99 module (the same emitter and CSE as ``generated/*.c``), the variables with names, SI units,
  causality and variability, and the native run's main table to compare with;
* :mod:`symmech.export.trolley` does it for the elastic trolley: its invariants and frame table as C data in
  front of the generic sums of ``c/elastic_trolley.c``, the native run's columns as calculated outputs;
* :mod:`symmech.export.grain` does it for the grain: the generated flight and sliding modules behind the regimes of
  ``c/grain.c`` (flight, slip, stick as a discrete state; the native engine's transitions at the events);
* :mod:`symmech.export.description` writes ``modelDescription.xml`` (FMI 2.0 and 3.0);
* :mod:`symmech.export.sources` lays out the C sources: the generated module, ``model.h``, the hand-written
  glue in ``c/`` (FMI 2 and 3, the linear solve and DOP853) and the DOP853 tableau from
  :mod:`symmech.numerics.dop853`;
* :mod:`symmech.export.build` compiles with the system C compiler and packs the FMU or the C folder.

The kinds covered, the variables and what is not done yet: docs/export.md.
"""
