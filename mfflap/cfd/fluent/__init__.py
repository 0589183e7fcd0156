"""Fluent adapter: DEFINE_CG_MOTION UDFs (analytic and table-driven), a batch journal, and a
parser of report files (.out). Fluent does not run here; every generated file is compiled or
parsed for real in the tests."""
