"""LIF 1.0 (VDMA Layout Interchange Format): reading, checking and writing layout files.

- `parse.parse_lif`: JSON → `document.LifDocument`, or a report of every problem by JSON path.
- `ids`: the rule for id clashes between several LIF files of one site (prefix by project).
- `export.export_lif`: maps → a LIF document.

Writing an import into the database is `maps.services.import_lif`.
"""
