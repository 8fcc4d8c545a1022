"""Moving least squares approximations (pure numpy, no MPI)."""

from geofrac.mls.shape import LinearFit, linear_fit, quartic_spline

__all__ = ["LinearFit", "linear_fit", "quartic_spline"]
