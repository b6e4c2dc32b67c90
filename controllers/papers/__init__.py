"""One package per source paper, named by its first author and year: its published constants and
paper-only recipes (``__init__``) and the controller kinds it names (``kinds``).  The paper's
reproduction is ``twin/reproductions/<paper>/``, its page ``docs/pages/papers/<paper>.md`` and its
results ``docs/results/<paper>.json``; controllers never import the twin, so the package stops here."""

#: The papers in the order of the source texts (shared/seeds/README.md): kinds register in it.
PAPERS = ("yadav2020", "sabau2022", "anang2017", "maharof2021", "choi1999")
