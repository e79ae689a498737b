"""What every stage shares: errors, transactional outputs, seeds, provenance, progress,
the data formats and configuration fields.

Kept free of imports so that the command line starts without numpy; import the
modules themselves (``from hesspipe.core.formats import read_run``).
"""
