"""Reports: KPIs, charts and CSV exports for managers (issue 9)."""
