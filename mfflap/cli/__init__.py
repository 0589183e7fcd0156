"""The ``mfflap`` command line: a thin layer over the library."""
