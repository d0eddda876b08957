"""The Random Decrement analysis: signatures (paper eqs. 8, 18-20), the estimator registry,
the estimators of ``e`` (eqs. 25-27, ``e_v``) and the one path from records to windows ×
estimators."""
