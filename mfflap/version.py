"""The package's version, in a module of its own so that every layer can name it without
importing the package's top level (which offers the facade of every layer)."""

__version__ = "0.1.0"
