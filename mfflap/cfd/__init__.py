"""CFD adapters: Motion -> case files, case -> Loads (OpenFOAM; Fluent to follow)."""
