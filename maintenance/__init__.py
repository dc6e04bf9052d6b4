"""Maintenance: service plans, work orders and the availability of vehicles (issue 7)."""
