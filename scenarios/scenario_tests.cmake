# Scenario regression tests (filled below)
