"""Ball-screw feed drive (Nguyen-Quoc et al.): parameters, modes, RK4 response, UKF identification, test planning."""

from mtident.feeddrive.identification import FeedDriveIdentification
from mtident.feeddrive.identify import default_guess, identify_feed_drive
from mtident.feeddrive.model import Excitation
from mtident.feeddrive.modes import Modes, modes, sampling_problem
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters, load_parameters, parameter_template, validate
from mtident.feeddrive.plan import (
    CandidateTest,
    ExcitationPlan,
    PlanPrediction,
    candidate_tests,
    plan_tests,
    predict_test,
)
from mtident.feeddrive.simulate import Response, read_response, simulate, write_response
from mtident.feeddrive.synthetic import random_drive, random_guess

__all__ = [
    "IDENTIFIED",
    "Excitation",
    "FeedDriveIdentification",
    "FeedDriveParameters",
    "Modes",
    "Response",
    "CandidateTest",
    "ExcitationPlan",
    "PlanPrediction",
    "candidate_tests",
    "default_guess",
    "identify_feed_drive",
    "load_parameters",
    "modes",
    "parameter_template",
    "plan_tests",
    "predict_test",
    "random_drive",
    "random_guess",
    "read_response",
    "sampling_problem",
    "simulate",
    "validate",
    "write_response",
]
