"""The papers' reproductions, one package per paper named as in :mod:`controllers.papers`, each
registering a :class:`~twin.reproductions.base.Reproduction`.  :mod:`twin.reproductions.registry`
imports them all (in the order of the source texts), so a new reproduction is one new package,
its name in :data:`controllers.papers.PAPERS` and its tests; ``twin reproduce PAPER`` and
``twin.reproduce`` dispatch through it, ``twin sweep`` asks each for certificates.

Importing this package loads no paper: the command line reads its defaults here at start-up.
"""

#: ``twin reproduce``'s defaults: Monte Carlo samples, random twin samples, seed.
DEFAULT_SAMPLES, DEFAULT_TWIN_SAMPLES, DEFAULT_SEED = 1000, 20, 0
