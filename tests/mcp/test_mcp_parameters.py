"""list_parameters, get_parameter and set_parameter through an MCP session, in both dialects."""

from __future__ import annotations

from mcp_harness import Session, open_session, parameter_names, text_of

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import Act, AskPerson
from rosbridge_mcp_server.sim import SimulatedRobot


def background_r(robot: SimulatedRobot) -> str:
    return "/turtlesim:background_r" if robot.dialect == "ros2" else "/turtlesim/background_r"


async def test_a_nodes_parameters_are_listed_in_the_dialects_naming(
    session: Session, sim: SimulatedRobot
) -> None:
    """/turtlesim lists background_r as /turtlesim:background_r (ROS 2) or /turtlesim/background_r (ROS 1)."""
    result = await session.ok("list_parameters", {"node": "/turtlesim"})
    names = parameter_names(result.structured_content)
    assert background_r(sim) in names
    assert all(name.startswith("/turtlesim") for name in names)


async def test_all_parameters_are_listed_without_a_node(session: Session, sim: SimulatedRobot) -> None:
    """Without a node every node's parameters are listed, grouped by node, sorted."""
    result = await session.ok("list_parameters")
    names = parameter_names(result.structured_content)
    assert background_r(sim) in names
    groups = (result.structured_content or {})["nodes"]
    assert [g["node"] for g in groups] == sorted(g["node"] for g in groups)
    assert all(g["names"] == sorted(g["names"]) for g in groups)


async def test_a_parameter_is_read_as_json(session: Session, sim: SimulatedRobot) -> None:
    """background_r reads 69, an integer."""
    result = await session.ok("get_parameter", {"name": background_r(sim)})
    assert (result.structured_content or {})["value"] == 69
    assert text_of(result) == f"{background_r(sim)} = 69"


async def test_a_parameter_is_set_and_read_back(session: Session, sim: SimulatedRobot) -> None:
    """Setting background_r to 200 changes it on the robot, and the answer says what it was."""
    result = await session.ok("set_parameter", {"name": background_r(sim), "value": 200})
    data = result.structured_content
    assert data is not None
    assert (data["previous"], data["value"], data["applied"]) == (69, 200, True)
    again = await session.ok("get_parameter", {"name": background_r(sim)})
    assert (again.structured_content or {})["value"] == 200


async def test_a_number_sent_as_text_is_decoded(session: Session, sim: SimulatedRobot) -> None:
    """ "120" for an integer parameter is taken as 120."""
    result = await session.ok("set_parameter", {"name": background_r(sim), "value": "120"})
    assert (result.structured_content or {})["value"] == 120


async def test_a_missing_parameter_is_an_error(session: Session, sim: SimulatedRobot) -> None:
    """A parameter that does not exist is an error naming it."""
    name = "/turtlesim:no_such" if sim.dialect == "ros2" else "/turtlesim/no_such"
    text = await session.error("get_parameter", {"name": name})
    assert "no_such" in text
    assert "does not exist" in text or "has no parameter" in text


async def test_a_name_in_the_other_dialects_form_is_an_error(session: Session, sim: SimulatedRobot) -> None:
    """A ROS 1 name on ROS 2 (and the reverse) is refused with the right form."""
    name = "/turtlesim/background_r" if sim.dialect == "ros2" else "/turtlesim:background_r"
    text = await session.error("get_parameter", {"name": name})
    assert "/turtlesim" in text
    assert "look like /node:name" in text or "ROS 2 style name" in text


async def test_a_null_value_is_refused_and_nothing_is_set(session: Session, sim: SimulatedRobot) -> None:
    """value null is an error; the parameter keeps its value."""
    text = await session.error("set_parameter", {"name": background_r(sim), "value": None})
    assert "null" in text
    result = await session.ok("get_parameter", {"name": background_r(sim)})
    assert (result.structured_content or {})["value"] == 69


async def test_an_unknown_node_is_an_error(session: Session, sim: SimulatedRobot) -> None:
    """Parameters of a node that does not run are an error suggesting the real one."""
    text = await session.error("list_parameters", {"node": "/turtlesimm"})
    assert "/turtlesimm" in text
    assert "Did you mean /turtlesim?" in text


async def test_a_ros2_value_of_another_type_is_refused(session_ros2: Session) -> None:
    """ROS 2 keeps a parameter's type: a string for an integer is an error saying so, and nothing changes."""
    text = await session_ros2.error("set_parameter", {"name": "/turtlesim:background_r", "value": "red"})
    assert "/turtlesim:background_r was not changed" in text
    assert "69" in text


class RefusingGuard:
    """Refuses every act, keeping what it was asked."""

    def __init__(self) -> None:
        self.asked: list[Act] = []

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        self.asked.append(act)
        raise PolicyRefusal("rule 'read only': parameters stay as they are")

    def record(self, act: Act, outcome: str) -> None:
        return None

    def held(self) -> str | None:
        return None

    def send_interval(self, act: Act) -> float:
        return 0.0


async def test_a_set_goes_through_the_safety_seam(sim_ros1: SimulatedRobot) -> None:
    """The guard sees a parameter act with the value; its refusal is the answer and nothing is set."""
    guard = RefusingGuard()
    async with open_session(sim_ros1.url, guard=guard) as session:
        text = await session.error("set_parameter", {"name": "/turtlesim/background_r", "value": 1})
        after = await session.ok("get_parameter", {"name": "/turtlesim/background_r"})
    assert "rule 'read only'" in text
    [act] = guard.asked
    assert (act.tool, act.kind, act.name, act.payload) == (
        "set_parameter",
        "parameter",
        "/turtlesim/background_r",
        1,
    )
    assert (after.structured_content or {})["value"] == 69


async def test_small_pages_walk_every_parameter_once_across_the_nodes(session: Session) -> None:
    """Pages of 7, from offset 0 on, give the same names in the same order as the whole listing, each page
    starting where the last ended (inside a node's names or at a new node) and saying how many are left."""
    whole = (await session.ok("list_parameters", {"limit": 1000})).structured_content
    assert whole is not None
    everything = parameter_names(whole)
    walked: list[str] = []
    while True:
        page = (await session.ok("list_parameters", {"limit": 7, "offset": len(walked)})).structured_content
        assert page is not None
        names = parameter_names(page)
        assert page["count"] == len(everything)
        assert page["more"] == len(everything) - len(walked) - len(names)
        walked += names
        if not page["more"]:
            break
        assert len(names) == 7
    assert walked == everything
    assert len(everything) > 14
