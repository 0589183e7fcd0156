"""Identification of force-model coefficients from time-resolved CFD forces."""

from mfflap.identification.data import CaseData, prepare_cases
from mfflap.identification.fit import IdentificationResult, identify
from mfflap.identification.weights import STRATEGIES, frequency_weights

__all__ = ["STRATEGIES", "CaseData", "IdentificationResult", "frequency_weights", "identify",
           "prepare_cases"]
