"""Self-contained HTML reports (figures embedded as PNG) whose numbers live in HDF5."""
