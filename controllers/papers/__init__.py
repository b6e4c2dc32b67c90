"""Each paper's published constants and paper-only recipes, one module per seed."""
