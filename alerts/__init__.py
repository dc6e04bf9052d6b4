"""Alerts: alert records from VDA 5050 errors, timeouts, battery and maintenance (issue 8).

Acknowledge, resolve and escalate.
"""
