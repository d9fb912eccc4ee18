"""Torque schedules for a robot controller: one segment, or a whole plan (CSV and JSON)."""
