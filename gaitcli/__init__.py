"""gaitcli: gait-lab processing from C3D trials to joint moments, muscle forces and predictive gait."""

__version__ = "0.1.0"
