"""Design procedures: python-control models in, controllers (LTI models or blocks) out.

Tested on python-control models alone, never on MuJoCo.
"""
