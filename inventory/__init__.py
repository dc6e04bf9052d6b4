"""Inventory: load carriers, storage locations and what is where, fed by pick/drop and state.loads (issue 8)."""
