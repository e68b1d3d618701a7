"""How a fit is solved: the global search (:mod:`.search`: Sobol screening, exploring local fits,
polish), the bounded Levenberg-Marquardt (:mod:`.bounded`), the constrained one
(:mod:`.constrained`), first-order optimality at bounds (:mod:`.stationary`) and one BLAS thread
during a fit (:mod:`.threads`). Imports only :mod:`roughbrdf.fitting.problem`.
"""
