"""The Nav2 world: builds one robot's Nav2 graph (or a fleet's, under ``/robotN``) on the kit's bridge, and
runs the goals of its action servers (navigating moves the robot to the goal)."""

from __future__ import annotations

import asyncio
import contextlib
import functools
import math
import time
from collections.abc import Callable, Sequence
from typing import Any, Literal

from rosbridge_mcp_server.sim.actions import ActionServer, GoalHandle
from rosbridge_mcp_server.sim.actions.ros2 import FeedbackFn
from rosbridge_mcp_server.sim.graph import ServiceEntry
from rosbridge_mcp_server.sim.nodes.kit import NodeKit
from rosbridge_mcp_server.sim.nodes.nav2.actionlib import ActionlibServer
from rosbridge_mcp_server.sim.nodes.nav2.health import Health
from rosbridge_mcp_server.sim.nodes.nav2.layout import (
    CONTROLLERS,
    LIFECYCLE_NODES,
    MANAGERS,
    NAV2_ACTIONS,
    NAV2_NODES,
    published,
    subscribed,
)
from rosbridge_mcp_server.sim.nodes.nav2.lifecycle import Lifecycles
from rosbridge_mcp_server.sim.nodes.nav2.motion import Motion
from rosbridge_mcp_server.sim.nodes.nav2.navigation import Navigator
from rosbridge_mcp_server.sim.nodes.nav2.params import NODE_PARAMETERS, common_parameters
from rosbridge_mcp_server.sim.nodes.nav2.robot import Nav2Robot, pose
from rosbridge_mcp_server.sim.nodes.nav2.surroundings import Surroundings, TurtleRoom
from rosbridge_mcp_server.sim.world import TURTLE_ARENA

__all__ = ["GOAL_STEPS", "Nav2ActionServer", "Nav2World"]

#: Steps a goal of a Nav2 action runs before it succeeds (one feedback each).
GOAL_STEPS = 4
#: The actions whose goals drive the robot along a plan (the others run GOAL_STEPS steps).
DRIVING_ACTIONS = ("navigate_to_pose", "navigate_through_poses")


def _yaw_of(orientation: Any) -> float:
    if not isinstance(orientation, dict):
        return 0.0
    z, w = float(orientation.get("z", 0.0)), float(orientation.get("w", 1.0))
    return 2 * math.atan2(z, w)


class Nav2ActionServer(ActionServer):
    """A Nav2 action server: a goal runs :data:`GOAL_STEPS` steps (one feedback each) and succeeds."""

    def __init__(
        self,
        world: Nav2World,
        robot: Nav2Robot,
        *,
        name: str,
        action_type: str,
        node: str,
        on_success: Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]] | None,
    ) -> None:
        super().__init__(world.kit.bridge, name, action_type, node)
        self.nav2 = world
        self.robot = robot
        self.on_success = on_success
        #: Every goal this server accepted, as it arrived (tests read what got through).
        self.received: list[dict[str, Any]] = []

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        self.received.append(goal)
        return True

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        if self.name.rsplit("/", 1)[-1] in DRIVING_ACTIONS:
            return await self._navigate(handle, feedback)
        step = self.nav2.action_step
        for index in range(GOAL_STEPS):
            if handle.cancel.is_set():
                return "canceled", {}
            feedback(self._feedback(handle.goal, index))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(handle.cancel.wait(), step)
        if handle.cancel.is_set():
            return "canceled", {}
        result = self.on_success(self.robot, handle.goal) if self.on_success is not None else {}
        self.nav2.kit.world.notify()
        return "succeeded", result

    async def _navigate(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        through = self.type.endswith("NavigateThroughPoses")

        def send(values: dict[str, Any]) -> None:
            if not through:
                values.pop("number_of_poses_remaining", None)
            feedback(values)

        outcome = await self.nav2.navigator.navigate(self.robot, handle.goal, handle.cancel, send)
        self.nav2.kit.world.notify()
        return outcome.state, {"error_code": outcome.error_code, "error_msg": outcome.error_msg}

    def _feedback(self, goal: dict[str, Any], index: int) -> dict[str, Any]:
        left = GOAL_STEPS - index
        leaf = self.type.rsplit("/", 1)[-1]
        if leaf.startswith("Navigate"):
            return {
                "current_pose": {
                    "header": {"frame_id": "map"},
                    "pose": pose(self.robot.x, self.robot.y, 0.0),
                },
                "distance_remaining": float(left),
                "number_of_recoveries": 0,
            }
        if leaf == "FollowPath":
            return {"distance_to_goal": float(left), "speed": 0.3}
        if leaf == "Spin":
            return {"angular_distance_traveled": abs(float(goal.get("target_yaw", 0.0))) * index / GOAL_STEPS}
        if leaf in ("BackUp", "DriveOnHeading"):
            return {"distance_traveled": 0.1 * index}
        if leaf == "FollowWaypoints":
            return {"current_waypoint": index}
        return {}


class Nav2World:
    """Builds the Nav2 graph (one robot, or a fleet under ``/robotN``) on the kit's bridge."""

    def __init__(
        self,
        kit: NodeKit,
        *,
        robots: int = 1,
        action_step: float = 0.2,
        type_descriptions: bool = True,
        surroundings: Surroundings | None = None,
        faults: Sequence[str] = (),
    ) -> None:
        if robots < 1:
            raise ValueError("robots must be >= 1")
        self.kit = kit
        self.ros2 = kit.ros2
        self.action_step = action_step
        self.type_descriptions = type_descriptions
        namespaces = [""] if robots == 1 else [f"/robot{i}" for i in range(1, robots + 1)]
        self.robots = [Nav2Robot(ns) for ns in namespaces]
        self.motion = Motion(kit, self.robots, surroundings or TurtleRoom())
        #: Plans on the map and drives the robots to navigation goals (``navigator.speed`` scales speeds).
        self.navigator = Navigator(kit, self._grid)
        self.lifecycles = Lifecycles(kit)
        #: /diagnostics, /rosout, the drivers' topics and the faults set on purpose (health.py).
        self.health = Health(kit, self.robots, faults)
        self.actions: list[Nav2ActionServer] = []
        #: ROS 1: the actionlib servers by action name (``/move_base``, ``/navigate_to_pose``, ...).
        self.actionlib: dict[str, ActionlibServer] = {}
        #: Every node of the world (absolute names), for the plumbing every node gets.
        self.node_names: list[str] = []

    def _grid(self) -> Any:
        return self.motion.surroundings.grid()

    @property
    def surroundings(self) -> Surroundings:
        """What the robots' map and laser see; set it before the robot starts to plug in another room."""
        return self.motion.surroundings

    @surroundings.setter
    def surroundings(self, surroundings: Surroundings) -> None:
        self.motion.surroundings = surroundings

    # --- names and types -----------------------------------------------------------------------------

    def _type(self, ros2_name: str, kind: Literal["msg", "srv", "action"] = "msg") -> str | None:
        pkg, _, leaf = ros2_name.split("/")
        return self.kit.type(ros2_name, f"{pkg}/{leaf}", kind)

    @property
    def _sep(self) -> str:
        return ":" if self.ros2 else "/"

    # --- building ------------------------------------------------------------------------------------

    def build(self) -> None:
        """Register every robot's nodes, topics, services, actions and parameters."""
        for robot in self.robots:
            self._build_robot(robot)
        self.health.build()
        self.kit.loops.append(self.motion.motion_loop)
        self.kit.loops.append(self.motion.sensor_loop)

    def _build_robot(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        nodes = [f"{ns}/{node}" for node in NAV2_NODES]
        self.node_names.extend(nodes)
        for node in nodes:
            self.kit.graph.node(node)
        self._topics(robot)
        self._services(robot)
        if self.ros2:
            for node in LIFECYCLE_NODES:
                robot.states[node] = 3
                self._lifecycle(robot, node)
            self._actions(robot)
        else:
            self._actionlib_topics(robot)
        self._goal_pose(robot)
        self._parameters(robot)

    def _topics(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        kit = self.kit
        twist = "geometry_msgs/msg/TwistStamped" if self.ros2 else "geometry_msgs/msg/Twist"
        for node, topic, ros2_type, latched in published(twist):
            kit.publisher(f"{ns}/{node}", f"{ns}/{topic}", self._type(ros2_type), latched=latched)
        for node, topic, ros2_type in subscribed(twist):
            msg_type = self._type(ros2_type)
            if msg_type is None:
                continue
            kit.graph.add_subscriber(f"{ns}/{node}", f"{ns}/{topic}", msg_type)
        # The robot follows what reaches twist_mux on cmd_vel (velocity_smoother and collision_monitor
        # pass a command through unchanged here).
        twist_type = self._type(twist)
        if twist_type is not None:
            kit.graph.add_subscriber(f"{ns}/twist_mux", f"{ns}/cmd_vel", twist_type, self._on_cmd_vel(robot))
        bond = self._type("bond/msg/Status")
        if bond is not None:
            for node in (*LIFECYCLE_NODES, *MANAGERS):
                kit.graph.add_publisher(f"{ns}/{node}", f"{ns}/bond", bond)
                kit.graph.add_subscriber(f"{ns}/{node}", f"{ns}/bond", bond)

    def _on_cmd_vel(self, robot: Nav2Robot) -> Callable[[dict[str, Any], int], None]:
        def follow(msg: dict[str, Any], _source: int) -> None:
            twist = msg.get("twist", msg)
            robot.linear = float(twist.get("linear", {}).get("x", 0.0))
            robot.angular = float(twist.get("angular", {}).get("z", 0.0))
            robot.command_time = time.monotonic()
            robot.commands += 1
            self.kit.world.notify()

        return follow

    def _service(self, node: str, name: str, ros2_type: str, handler: Any = None) -> None:
        service_type = self._type(ros2_type, "srv")
        if service_type is not None:
            self.kit.graph.add_service(ServiceEntry(name, service_type, node, handler or self._empty))

    @staticmethod
    async def _empty(request: dict[str, Any]) -> dict[str, Any]:
        return {}

    def _services(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        for manager in MANAGERS:
            managed = NODE_PARAMETERS[manager]["node_names"]
            node = f"{ns}/{manager}"
            self._service(
                node,
                f"{node}/manage_nodes",
                "nav2_msgs/srv/ManageLifecycleNodes",
                self.lifecycles.manage(robot, managed),
            )
            self._service(
                node, f"{node}/is_active", "std_srvs/srv/Trigger", self.lifecycles.is_active(robot, managed)
            )
        for server in ("map_server", "filter_mask_server"):
            self._service(
                f"{ns}/{server}", f"{ns}/{server}/load_map", "nav2_msgs/srv/LoadMap", self._load_map
            )
            self._service(f"{ns}/{server}", f"{ns}/{server}/map", "nav_msgs/srv/GetMap", self._get_map)
        self._service(f"{ns}/map_saver", f"{ns}/map_saver/save_map", "nav2_msgs/srv/SaveMap", self._saved)
        for leaf, srv in (
            ("reinitialize_global_localization", "std_srvs/srv/Empty"),
            ("request_nomotion_update", "std_srvs/srv/Empty"),
            ("set_initial_pose", "nav2_msgs/srv/SetInitialPose"),
        ):
            self._service(f"{ns}/amcl", f"{ns}/{leaf}", srv)
        for costmap in ("global_costmap", "local_costmap"):
            node = f"{ns}/{costmap}/{costmap}"
            for kind, srv in (
                ("clear_entirely", "nav2_msgs/srv/ClearEntireCostmap"),
                ("clear_around", "nav2_msgs/srv/ClearCostmapAroundRobot"),
                ("clear_except", "nav2_msgs/srv/ClearCostmapExceptRegion"),
            ):
                self._service(node, f"{ns}/{costmap}/{kind}_{costmap}", srv)
            self._service(node, f"{ns}/{costmap}/get_costmap", "nav2_msgs/srv/GetCostmap")
        self._service(
            f"{ns}/planner_server",
            f"{ns}/planner_server/is_path_valid",
            "nav2_msgs/srv/IsPathValid",
            self._path_valid,
        )
        self._service(
            f"{ns}/docking_server", f"{ns}/docking_server/reload_database", "nav2_msgs/srv/ReloadDockDatabase"
        )
        manager = f"{ns}/controller_manager"
        for leaf, srv in (
            ("configure_controller", "ConfigureController"),
            ("list_controller_types", "ListControllerTypes"),
            ("list_controllers", "ListControllers"),
            ("list_hardware_components", "ListHardwareComponents"),
            ("list_hardware_interfaces", "ListHardwareInterfaces"),
            ("load_controller", "LoadController"),
            ("reload_controller_libraries", "ReloadControllerLibraries"),
            ("set_hardware_component_state", "SetHardwareComponentState"),
            ("switch_controller", "SwitchController"),
            ("unload_controller", "UnloadController"),
        ):
            handler = self._list_controllers if leaf == "list_controllers" else self._ok
            self._service(manager, f"{manager}/{leaf}", f"controller_manager_msgs/srv/{srv}", handler)
        for leaf, srv in (
            ("set_pose", "robot_localization/srv/SetPose"),
            ("toggle", "robot_localization/srv/ToggleFilterProcessing"),
            ("enable", "std_srvs/srv/Empty"),
        ):
            self._service(f"{ns}/ekf_filter_node", f"{ns}/{leaf}", srv)

    @staticmethod
    async def _saved(request: dict[str, Any]) -> dict[str, Any]:
        return {"result": True}

    @staticmethod
    async def _ok(request: dict[str, Any]) -> dict[str, Any]:
        return {"ok": True}

    async def _list_controllers(self, request: dict[str, Any]) -> dict[str, Any]:
        return {
            "controller": [
                {"name": name, "state": "active", "type": kind, "update_rate": 50}
                for name, kind in CONTROLLERS
            ]
        }

    async def _path_valid(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"is_valid": True, "invalid_pose_indices": []}

    async def _get_map(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"map": self.motion.map_message()}

    async def _load_map(self, request: dict[str, Any]) -> dict[str, Any]:
        return {"map": self.motion.map_message(), "result": 0}

    def _lifecycle(self, robot: Nav2Robot, name: str) -> None:
        node = f"{robot.namespace}/{name}"
        self.kit.publisher(node, f"{node}/transition_event", self._type("lifecycle_msgs/msg/TransitionEvent"))
        for leaf, srv, handler in self.lifecycles.handlers(robot, name):
            self._service(node, f"{node}/{leaf}", srv, handler)

    @staticmethod
    def _succeed(
        behaviour: Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]],
        robot: Nav2Robot,
        goal: dict[str, Any],
    ) -> None:
        behaviour(robot, goal)

    def _behaviours(self) -> dict[str, Callable[[Nav2Robot, dict[str, Any]], dict[str, Any]]]:
        """What a succeeding goal of each action does to the robot (and answers)."""
        return {
            "navigate_to_pose": self._arrive,
            "navigate_through_poses": self._arrive,
            "follow_waypoints": self._arrive,
            "compute_path_to_pose": self._plan,
            "compute_path_through_poses": self._plan,
            "spin": self._spin,
        }

    def _actions(self, robot: Nav2Robot) -> None:
        ns = robot.namespace
        behaviours = self._behaviours()
        for name, leaf, node in NAV2_ACTIONS:
            action_type = self._type(f"nav2_msgs/action/{leaf}", "action")
            if action_type is None:
                continue
            self.actions.append(
                Nav2ActionServer(
                    self,
                    robot,
                    name=f"{ns}/{name}",
                    action_type=action_type,
                    node=f"{ns}/{node}",
                    on_success=behaviours.get(name),
                )
            )

    def _actionlib_topics(self, robot: Nav2Robot) -> None:
        """ROS 1: each action as an actionlib server over its five topics, and ROS 1's ``move_base``."""
        ns = robot.namespace
        if self._type("move_base_msgs/msg/MoveBaseActionGoal") is not None:
            self.kit.graph.node(f"{ns}/move_base")
            self.actionlib[f"{ns}/move_base"] = ActionlibServer(
                self.kit,
                name=f"{ns}/move_base",
                node=f"{ns}/move_base",
                package="move_base_msgs",
                action="MoveBase",
                steps=GOAL_STEPS,
                step=self.action_step,
                runner=functools.partial(self._drive_ros1, robot, ros1_feedback=True),
            )
        for name, leaf, node in NAV2_ACTIONS:
            if self._type(f"nav2_msgs/msg/{leaf}ActionGoal") is None:
                continue
            if name in DRIVING_ACTIONS:
                self.actionlib[f"{ns}/{name}"] = ActionlibServer(
                    self.kit,
                    name=f"{ns}/{name}",
                    node=f"{ns}/{node}",
                    package="nav2_msgs",
                    action=leaf,
                    steps=GOAL_STEPS,
                    step=self.action_step,
                    runner=functools.partial(self._drive_ros1, robot, ros1_feedback=False),
                )
                continue
            behaviour = self._behaviours().get(name)
            on_success: Callable[[dict[str, Any]], None] | None = None
            if behaviour is not None:
                on_success = functools.partial(self._succeed, behaviour, robot)
            self.actionlib[f"{ns}/{name}"] = ActionlibServer(
                self.kit,
                name=f"{ns}/{name}",
                node=f"{ns}/{node}",
                package="nav2_msgs",
                action=leaf,
                steps=GOAL_STEPS,
                step=self.action_step,
                on_success=on_success,
            )

    def _goal_pose(self, robot: Nav2Robot) -> None:
        """A goal pose topic, as RViz's "2D Goal Pose" sends it: ROS 2 Nav2's bt_navigator makes it a
        NavigateToPose goal of its own (``/goal_pose``); ROS 1 move_base a goal of ``/move_base`` with no id,
        which the action server names (``/move_base_simple/goal``)."""
        ns = robot.namespace
        if self.ros2:
            navigator = next((a for a in self.actions if a.name == f"{ns}/navigate_to_pose"), None)
            if navigator is None:
                return

            def to_navigator(msg: dict[str, Any], _source: int) -> None:
                navigator.submit({"pose": msg, "behavior_tree": ""}, key=None, on_feedback=None)

            # bt_navigator already subscribes /goal_pose in the graph (layout.py): only its callback is added.
            self.kit.graph.local_subscribers.setdefault(f"{ns}/goal_pose", []).append(to_navigator)
            return
        move_base = self.actionlib.get(f"{ns}/move_base")
        pose_type = self._type("geometry_msgs/msg/PoseStamped")
        if move_base is None or pose_type is None:
            return

        def to_move_base(msg: dict[str, Any], source: int) -> None:
            move_base.take_goal({"goal_id": {}, "goal": {"target_pose": msg}}, source)

        topic = f"{ns}/move_base_simple/goal"
        self.kit.graph.add_subscriber(f"{ns}/move_base", topic, pose_type, to_move_base)

    async def _drive_ros1(
        self,
        robot: Nav2Robot,
        goal: dict[str, Any],
        cancel: asyncio.Event,
        feedback: Callable[[dict[str, Any]], None],
        *,
        ros1_feedback: bool,
    ) -> tuple[str, dict[str, Any]]:
        def send(values: dict[str, Any]) -> None:
            if not ros1_feedback:
                values.pop("number_of_poses_remaining", None)
            feedback(values)

        outcome = await self.navigator.navigate(robot, goal, cancel, send, ros1=ros1_feedback)
        self.kit.world.notify()
        result = {} if ros1_feedback else {"error_code": outcome.error_code, "error_msg": outcome.error_msg}
        return outcome.state, result

    def _parameters(self, robot: Nav2Robot) -> None:
        params = self.kit.world.params
        sep = self._sep
        common = common_parameters(type_descriptions=self.type_descriptions) if self.ros2 else {}
        for name in NAV2_NODES:
            node = f"{robot.namespace}/{name}"
            for key, value in {**common, **NODE_PARAMETERS.get(name, {})}.items():
                params[f"{node}{sep}{key if self.ros2 else key.replace('.', '/')}"] = value

    # --- what the goals do ---------------------------------------------------------------------------

    def _goalpose(self, goal: dict[str, Any]) -> tuple[float, float, float] | None:
        pose_msg = goal.get("pose") or goal.get("goal")
        if pose_msg is None:
            poses = goal.get("poses") or goal.get("goals") or []
            if isinstance(poses, dict):  # Kilted's nav_msgs/Goals
                poses = poses.get("goals") or []
            pose_msg = poses[-1] if poses else None
        if not isinstance(pose_msg, dict):
            return None
        pose = pose_msg.get("pose", {})
        position = pose.get("position", {})
        return float(position.get("x", 0.0)), float(position.get("y", 0.0)), _yaw_of(pose.get("orientation"))

    def _path(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        target = self._goalpose(goal) or (robot.x, robot.y, robot.yaw)
        count = 20
        poses = [
            {
                "header": self.kit.header("map"),
                "pose": pose(
                    robot.x + (target[0] - robot.x) * i / count,
                    robot.y + (target[1] - robot.y) * i / count,
                    target[2],
                ),
            }
            for i in range(count + 1)
        ]
        return {"header": self.kit.header("map"), "poses": poses}

    def _plan(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        path = self._path(robot, goal)
        self.kit.publish(f"{robot.namespace}/plan", path)
        return {"path": path, "planning_time": {"sec": 0, "nanosec": 20_000_000}}

    def _arrive(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        self.kit.publish(f"{robot.namespace}/plan", self._path(robot, goal))
        target = self._goalpose(goal)
        if target is not None:
            robot.x = min(max(target[0], 0.2), TURTLE_ARENA - 0.2)
            robot.y = min(max(target[1], 0.2), TURTLE_ARENA - 0.2)
            robot.yaw = target[2]
        return {}

    def _spin(self, robot: Nav2Robot, goal: dict[str, Any]) -> dict[str, Any]:
        turn = float(goal.get("target_yaw", 0.0))
        robot.yaw = math.atan2(math.sin(robot.yaw + turn), math.cos(robot.yaw + turn))
        return {}

    async def close(self) -> None:
        """Stop every goal (the robot is shutting down)."""
        for server in self.actions:
            await server.close()
