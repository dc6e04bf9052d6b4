"""Robots: the vehicle registry with identity, factsheet, connection and the live state snapshot."""
