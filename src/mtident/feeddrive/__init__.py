"""Ball-screw feed drive (seed 004): parameters, modes, RK4 response, UKF identification."""

from mtident.feeddrive.identify import FeedDriveIdentification, default_guess, identify_feed_drive
from mtident.feeddrive.model import Excitation
from mtident.feeddrive.modes import Modes, modes
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters, load_parameters, validate
from mtident.feeddrive.simulate import Response, read_response, simulate, write_response

__all__ = [
    "IDENTIFIED",
    "Excitation",
    "FeedDriveIdentification",
    "FeedDriveParameters",
    "Modes",
    "Response",
    "default_guess",
    "identify_feed_drive",
    "load_parameters",
    "modes",
    "read_response",
    "simulate",
    "validate",
    "write_response",
]
