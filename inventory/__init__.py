"""Inventory: load carriers, storage locations and what is where (issue 8).

Fed by finished pick/drop actions and the vehicles' state.loads.
"""
