"""hpa-sim's Python side: a flight-stack client for the lockstep protocol (lockstep: run for a
single vehicle, run_team for a team's vehicles), the payload reference a hello describes
(reference) and loaders of what a run writes (results). Standard library and numpy only. A file
the loaders cannot read is an InputError ("PATH:LINE:COLUMN: what was wrong, what was
expected"); a message the client cannot read is a ProtocolError naming the message."""

from .lockstep import FlightStackClient, Command, RotorCommand, Tick, PROTOCOL_VERSION  # noqa: F401
from .lockstep import run, run_team, TeamView  # noqa: F401
from .lockstep import ProtocolError  # noqa: F401
from .reference import PayloadReference  # noqa: F401
from .results import InputError, load_log, load_metrics, load_runs  # noqa: F401
