"""Alerts: alert records from VDA 5050 errors, timeouts, battery and maintenance; acknowledge and resolve (issue 8)."""
