//! Reports: PNG/SVG plots, REPORT.md builder and claims.json.
