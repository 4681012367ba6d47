"""LMI synthesis of gain pairs: the stage between the symbolic design and the certificates.

Like :mod:`switchobs.design`, it produces ``K_plus`` / ``K_minus`` for a model, here from linear matrix
inequalities with a decay rate in the rescaled time and an H2 noise bound (seed 004; seed 000 eq. (13)),
for the nominal model or jointly over a box of its parameters.  Every pair it returns carries exact
per-mode decay certificates checked in rational arithmetic; its stability under switching is then a
question for :mod:`switchobs.certify` (``switchobs synthesize`` runs both).

Public API
----------
synthesize          -- gains of a model at its values (the CLI's ``switchobs synthesize``)
synthesize_gains    -- gains of a matrix pair ``(A, C)``
synthesize_box      -- gains for every parameter value of a box (polytopic LMIs at the vertices)
noise_decay_front   -- the noise gain against the decay rate (one synthesis per rate and weight)
noise_gain          -- the H2 gain from measurement noise to the estimated states of one mode
GainSynthesis, FrontPoint -- the results (``to_json`` / ``from_json``)
decay_certificate, decay_holds -- per-mode exact decay certificates and their check
"""

from ._box_synthesis import synthesize_box
from ._synthesis import (FrontPoint, GainSynthesis, decay_certificate, decay_holds, noise_decay_front, noise_gain,
                         synthesize, synthesize_gains)

__all__ = ["FrontPoint", "GainSynthesis", "decay_certificate", "decay_holds", "noise_decay_front", "noise_gain",
           "synthesize", "synthesize_box", "synthesize_gains"]
