"""hpa-sim's Python side: a flight-stack client for the lockstep protocol (lockstep) and loaders
of what a run writes (results). Standard library and numpy only."""

from .lockstep import FlightStackClient, Command, Tick, PROTOCOL_VERSION, run  # noqa: F401
from .results import load_log, load_metrics, load_runs  # noqa: F401
