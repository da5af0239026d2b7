"""The runner: what a front door does around the pure core (docs/ARCHITECTURE.md). Checks and
``auto`` choices (:mod:`.checks`, :mod:`.choices`); compilation and every cache (:mod:`.xla`,
:mod:`.programs`, :mod:`.tables`); the host it hands the core (:mod:`.door`); threads,
pipelining and progress (:mod:`.pipeline`, :mod:`.progress`, :mod:`.batch`, :mod:`.threads`:
daemon threads that a Ctrl-C does not wait for); and the front
doors that return datasets (:mod:`.simulation`, :mod:`.batch`, :mod:`.frequency`,
:mod:`.spectral`, :mod:`.linear`), built by :mod:`mfm.results`."""
