"""Whole cams: motion programs in physical units, steady state at machine speed, jump, export."""

from ._dynamics import Solver as Solver
from ._dynamics import startup as startup
from ._spec import Follower as Follower
from ._spec import Program as Program
from ._spec import Segment as Segment
from ._spec import example_path as example_path
