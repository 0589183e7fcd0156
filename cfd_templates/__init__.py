"""The solver templates mfflap writes cases from, installed as ``mfflap.cfd_templates``:
``openfoam/`` (dictionaries, jinja2 where they carry numbers, the meshes and named
set-ups) and ``fluent/`` (UDF and journal templates, the stand-in header the tests
compile them against)."""
