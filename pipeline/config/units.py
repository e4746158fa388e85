"""Unit conversion factors to SI: a quantity in the unit times its factor is in SI units.

``1.5 * NM`` is 1.5 nm in metres; ``x / NM`` is ``x`` [m] in nanometres.
"""

NM = 1e-9   # nanometre [m]
UM = 1e-6   # micrometre [m]
MM = 1e-3   # millimetre [m]
MPA = 1e6   # megapascal [Pa]
GPA = 1e9   # gigapascal [Pa]
KHZ = 1e3   # kilohertz [Hz]
NS = 1e-9   # nanosecond [s]
US = 1e-6   # microsecond [s]
MS = 1e-3   # millisecond [s]
MN = 1e-3   # millinewton [N]
