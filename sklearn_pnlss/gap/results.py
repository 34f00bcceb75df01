"""Typed results of a diagnosis' fit, read by its report and its user."""
from typing import NamedTuple

__all__ = ["ChannelDelay"]


class ChannelDelay(NamedTuple):
    """A delay between the force and displacement channels that the
    training data carry (a sensor's, an anti-alias filter's): a property of
    the measurement chain, fitted with every candidate.

    Attributes
    ----------
    delay_s : float
        The delay, seconds (positive: the displacement lags the force).
    samples : float
        The same in samples of the data: the start of every candidate's
        delay parameter.
    gain_db : float
        How much freeing the delay improved the fit it was found on, dB.
    found_on : str
        That fit: ``"recalibration"`` (the nominal refitted, the first
        look) or the candidate it hid behind (a strong nonlinearity that
        the nominal's refit could not follow).
    """

    delay_s: float
    samples: float
    gain_db: float
    found_on: str
