"""The package's layout (its metadata is in pyproject.toml): mfflap, and the solver
templates of the top-level cfd_templates/ folder installed as mfflap.cfd_templates, which
mfflap.cfd.templates reads with importlib.resources."""

from setuptools import find_packages, setup

TEMPLATES = "mfflap.cfd_templates"

setup(
    packages=[*find_packages(include=["mfflap", "mfflap.*"]), TEMPLATES],
    package_dir={TEMPLATES: "cfd_templates"},
    package_data={TEMPLATES: ["*/*", "*/*/*", "*/*/*/*"]},
)
