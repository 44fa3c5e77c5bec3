"""Message, service and action types of the simulated robot, in ROS 1 and ROS 2 form.

``InterfaceRegistry(dialect)`` resolves type names as rosbridge's ``ros_loader`` does, produces rosapi's
``TypeDef`` lists and full definition texts, and converts JSON messages with rosbridge's strictness and error
texts (``from_json``) and to rosbridge's outbound JSON form (``to_json``).
"""

from .registry import ConversionError, Dialect, InterfaceError, InterfaceRegistry, Kind

__all__ = ["ConversionError", "Dialect", "InterfaceError", "InterfaceRegistry", "Kind"]
