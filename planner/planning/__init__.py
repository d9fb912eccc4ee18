"""Planning two-finger tasks (Section 5.2): tasks, contact-state checks, plans through OMPL, failure reports, re-simulation."""
