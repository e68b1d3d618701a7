"""The kinds of fit: channel by channel (:mod:`.channels`, the fit of one named model), all
channels at once (:mod:`.joint`), Mueller data (:mod:`.polarimetric`) and a parameter set per
incidence (:mod:`.per_incidence`). Above the problem, solver and result rooms and
:mod:`roughbrdf.fitting.energy`.
"""
