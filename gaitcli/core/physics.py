"""Physical constants of the model, SI units."""

#: gravitational acceleration, m/s², along −z (the dissertation's g; Earth's surface spans 9.78–9.83)
GRAVITY_M_S2 = 9.81
