"""OpenFOAM adapter: case writer, runner and force-log parser."""
