"""CFD records: the type every layer above reads (one finished CFD run, its kinematics,
loads and provenance), how it ran, and the screens applied to its loads before use."""
