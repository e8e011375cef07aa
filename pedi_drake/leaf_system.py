"""LeafSystemWithoutWitnesses: the base of this package's Python LeafSystems.

None of them declares a witness function, and Drake asks every system for its witness functions
after each unrestricted update: the plant's step in simulation, the mission manager's and the
live SUF's updates on the controller side. For a system written in Python, pydrake's
LeafSystem forwards that question to a Python override of `DoGetWitnessFunctions`, if there
is one. pybind11 remembers that a method is not overridden only when the attribute it finds is a
C++ function; when there is no attribute at all, it searches the class, fails and formats an
AttributeError at every call, for every Python system after every unrestricted update: a
cost paid many times a tick on the controller side of a hardware run. Naming the C++ method
`GetWitnessFunctions` as the attribute makes pybind11 remember after the first look that there
is no override, and Drake's own answer (no witness functions) is used.
"""

from pydrake.systems.framework import LeafSystem


class LeafSystemWithoutWitnesses(LeafSystem):
    """A LeafSystem with no witness functions, at no cost per unrestricted update (see the module
    docstring). Derive from it instead of LeafSystem."""

    # A C++ function in the attribute's place: pybind11 caches "not overridden in Python".
    DoGetWitnessFunctions = LeafSystem.GetWitnessFunctions
