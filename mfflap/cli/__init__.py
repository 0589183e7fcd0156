"""The ``mfflap`` command line: a thin layer over the library.

Each command imports the layers it uses inside its own function, so that ``mfflap --help``,
a command's ``--help`` and a refused option answer at once instead of after loading every
layer (numba's kernels, CasADi, matplotlib, dask); that is the one reason for the imports
inside functions here.
"""
