"""What a fit is asked to solve: one channel's samples (:mod:`.data`), the weighted residuals and
their finite-difference Jacobians (:mod:`.objective`), the options (:mod:`.options`,
:mod:`.search_options`), the plan checked before any work (:mod:`.plan`) and the channels'
wavelengths (:mod:`.wavelengths`). The lowest room of :mod:`roughbrdf.fitting`: it imports no
other room.
"""
