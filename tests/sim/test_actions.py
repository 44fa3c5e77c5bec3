"""The /fibonacci action: ROS 2 action ops and hidden services, ROS 1 actionlib topics, Humble ordering."""

from __future__ import annotations

import asyncio
import base64
import time
from typing import Any

import pytest
from rawclient import MakeSim, RawClient

from rosbridge_mcp_server.sim import SimulatedRobot

FIBONACCI = "example_interfaces/action/Fibonacci"


def goal_op(
    goal_id: str, order: int, *, feedback: bool = True, action_type: str = FIBONACCI
) -> dict[str, Any]:
    """A send_action_goal op for /fibonacci."""
    return {
        "op": "send_action_goal",
        "id": goal_id,
        "action": "/fibonacci",
        "action_type": action_type,
        "args": {"order": order},
        "feedback": feedback,
    }


async def test_ros2_goal_sends_one_feedback_per_step_then_the_result(sim_ros2: SimulatedRobot) -> None:
    """order 5: four feedbacks growing from [0, 1, 1], then action_result status 4 with the sequence."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(goal_op("g1", 5))
        feedbacks = [await client.reply("g1", op="action_feedback") for _ in range(4)]
        result = await client.reply("g1", op="action_result")
    assert [f["values"]["sequence"] for f in feedbacks] == [
        [0, 1, 1],
        [0, 1, 1, 2],
        [0, 1, 1, 2, 3],
        [0, 1, 1, 2, 3, 5],
    ]
    assert feedbacks[0]["action"] == "/fibonacci"
    assert result == {
        "op": "action_result",
        "id": "g1",
        "action": "/fibonacci",
        "result": True,
        "status": 4,
        "values": {"sequence": [0, 1, 1, 2, 3, 5]},
    }
    assert sim_ros2.world.goals["g1"].status == 4


async def test_ros2_goal_without_feedback_flag_gets_only_the_result(sim_ros2: SimulatedRobot) -> None:
    """feedback defaults to false: no action_feedback frames."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(goal_op("quiet", 3, feedback=False))
        result = await client.reply("quiet", op="action_result")
        frames = await client.frames_before_barrier()
    assert result["status"] == 4
    assert [f for f in frames if f.get("op") == "action_feedback"] == []


async def test_ros2_cancel_ends_the_goal_canceled_with_the_partial_sequence(sim_ros2: SimulatedRobot) -> None:
    """cancel_action_goal with the goal's id: status 5 (CANCELED) and the sequence so far."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(goal_op("long", 40))
        await client.reply("long", op="action_feedback")
        await client.send({"op": "cancel_action_goal", "id": "long", "action": "/fibonacci"})
        result = await client.reply("long", op="action_result")
    assert result["result"] is True
    assert result["status"] == 5
    sequence = result["values"]["sequence"]
    assert 3 <= len(sequence) < 41
    assert sequence[:4] == [0, 1, 1, 2][: len(sequence)]


@pytest.mark.parametrize("in_order", [False, True], ids=["jazzy", "humble"])
async def test_a_cancel_sent_on_another_connection_stops_the_goal(make_sim: MakeSim, in_order: bool) -> None:
    """rosbridge keeps one goal table per process: a cancel sent on a second socket stops the goal (on an
    in-order Humble bridge, the escape from the freeze of a goal's own connection)."""
    robot = await make_sim(dialect="ros2", in_order=in_order)
    async with await RawClient.open(robot.url) as owner, await RawClient.open(robot.url) as other:
        await owner.send(goal_op("shared", 40))
        await owner.reply("shared", op="action_feedback")
        await other.send({"op": "cancel_action_goal", "id": "shared", "action": "/fibonacci"})
        result = await owner.reply("shared", op="action_result")
    assert result["status"] == 5


async def test_ros2_cancel_of_an_unknown_goal_is_silent(sim_ros2: SimulatedRobot) -> None:
    """cancel_action_goal for an id nobody uses produces nothing."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send({"op": "cancel_action_goal", "id": "nobody", "action": "/fibonacci"})
        assert await client.frames_before_barrier() == []


async def test_ros2_negative_order_goal_is_rejected(sim_ros2: SimulatedRobot) -> None:
    """Our Fibonacci server rejects order < 0: 'Action goal was rejected', result false, status 0."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(goal_op("neg", -1))
        result = await client.reply("neg", op="action_result")
    assert result == {
        "op": "action_result",
        "id": "neg",
        "action": "/fibonacci",
        "result": False,
        "status": 0,
        "values": "Action goal was rejected",
    }


async def test_ros2_goal_whose_numbers_overflow_int32_is_aborted(make_sim: MakeSim) -> None:
    """From order 47 the next number does not fit int32: ABORTED (6) with the sequence so far."""
    robot = await make_sim(dialect="ros2", action_step=0.001)
    async with await RawClient.open(robot.url) as client:
        await client.send(goal_op("big", 60, feedback=False))
        result = await client.reply("big", op="action_result")
    assert result["status"] == 6
    assert len(result["values"]["sequence"]) == 47


async def test_ros2_goal_to_a_missing_action_server_fails_after_about_a_second(
    sim_ros2: SimulatedRobot,
) -> None:
    """No server for the action: 'No action server available' (2.0.5/2.5.0+), after rosbridge's 1 s wait."""
    async with await RawClient.open(sim_ros2.url) as client:
        started = time.monotonic()
        await client.send({**goal_op("none", 3), "action": "/no_such_action"})
        result = await client.reply("none", op="action_result")
    assert result["result"] is False
    assert result["values"] == "No action server available"
    assert time.monotonic() - started >= 0.9


async def test_ros2_goal_with_bad_args_fails_with_the_conversion_text(sim_ros2: SimulatedRobot) -> None:
    """Goal args that do not fit the goal type: action_result result false with the text."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send({**goal_op("bad", 3), "args": {"order": "five"}})
        result = await client.reply("bad", op="action_result")
    assert result["result"] is False
    assert result["status"] == 0
    assert isinstance(result["values"], str)
    assert "order" in result["values"]


async def test_ros2_graph_shows_the_hidden_action_topics_and_services(sim_ros2: SimulatedRobot) -> None:
    """rosapi lists hide /fibonacci/_action/*, action_servers and action_type find the action."""
    async with await RawClient.open(sim_ros2.url) as client:
        topics = await client.values("/rosapi/topics")
        services = await client.values("/rosapi/services")
        servers = await client.values("/rosapi/action_servers")
        action_type = await client.values("/rosapi/action_type", {"action": "/fibonacci"})
        node = await client.values("/rosapi/node_details", {"node": "/fibonacci_server"})
    assert not [t for t in topics["topics"] if "/_action/" in t]
    assert not [s for s in services["services"] if "/_action/" in s]
    assert servers["action_servers"] == ["/fibonacci"]
    assert action_type["type"] == FIBONACCI
    assert "/fibonacci/_action/status" in node["publishing"]
    assert "/fibonacci/_action/cancel_goal" in node["services"]


async def test_ros2_status_topic_reports_goal_states(sim_ros2: SimulatedRobot) -> None:
    """Subscribers of /fibonacci/_action/status see the goal executing and then succeeded."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(
            {
                "op": "subscribe",
                "topic": "/fibonacci/_action/status",
                "type": "action_msgs/msg/GoalStatusArray",
            }
        )
        await client.frames_before_barrier()
        await client.send(goal_op("watched", 2, feedback=False))
        seen: list[int] = []
        while 4 not in seen:
            status = await client.next_publish("/fibonacci/_action/status")
            seen = [s["status"] for s in status["msg"]["status_list"]]
    uuid = status["msg"]["status_list"][0]["goal_info"]["goal_id"]["uuid"]
    assert len(base64.b64decode(uuid)) == 16


async def test_ros2_hidden_cancel_goal_service_with_zero_id_cancels_every_goal(
    sim_ros2: SimulatedRobot,
) -> None:
    """CancelGoal with a zero UUID and zero stamp cancels all goals and lists them in goals_canceling."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send(goal_op("one", 40, feedback=False))
        await client.send(goal_op("two", 40, feedback=False))
        await sim_ros2.wait_for(lambda w: {"one", "two"} <= set(w.goals))
        response = await client.values(
            "/fibonacci/_action/cancel_goal",
            {"goal_info": {"goal_id": {"uuid": [0] * 16}, "stamp": {"sec": 0, "nanosec": 0}}},
        )
        results = [await client.reply(goal_id, op="action_result") for goal_id in ("one", "two")]
    assert response["return_code"] == 0
    assert len(response["goals_canceling"]) == 2
    assert [r["status"] for r in results] == [5, 5]


async def test_ros1_has_no_action_ops(sim_ros1: SimulatedRobot) -> None:
    """On ROS 1 send_action_goal is an unknown op: logged, never answered."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send(goal_op("g", 3, action_type="actionlib_tutorials/FibonacciAction"))
        assert await client.frames_before_barrier() == []
    assert sim_ros1.world.goals == {}


async def _ros1_send_goal(client: RawClient, goal_id: str, order: int) -> None:
    await client.send(
        {
            "op": "publish",
            "topic": "/fibonacci/goal",
            "msg": {"goal_id": {"id": goal_id}, "goal": {"order": order}},
        }
    )


async def test_ros1_actionlib_goal_gets_feedback_and_a_succeeded_result(sim_ros1: SimulatedRobot) -> None:
    """A goal on /fibonacci/goal: feedback on /fibonacci/feedback, result with status 3 (SUCCEEDED)."""
    async with await RawClient.open(sim_ros1.url) as client:
        for leaf in ("feedback", "result", "status"):
            await client.send({"op": "subscribe", "topic": f"/fibonacci/{leaf}"})
        await client.next_publish("/fibonacci/status")
        await _ros1_send_goal(client, "r1-goal", 4)
        feedback = await client.next_publish("/fibonacci/feedback")
        result = await client.next_publish("/fibonacci/result")
    assert feedback["msg"]["status"]["goal_id"]["id"] == "r1-goal"
    assert feedback["msg"]["status"]["status"] == 1
    assert feedback["msg"]["feedback"]["sequence"] == [0, 1, 1]
    assert result["msg"]["status"]["status"] == 3
    assert result["msg"]["result"]["sequence"] == [0, 1, 1, 2, 3]
    assert set(result["msg"]["header"]["stamp"]) == {"secs", "nsecs"}


async def test_ros1_cancel_preempts_the_goal_with_the_partial_sequence(sim_ros1: SimulatedRobot) -> None:
    """A GoalID on /fibonacci/cancel: the result comes with status 2 (PREEMPTED) and the sequence so far."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "subscribe", "topic": "/fibonacci/feedback"})
        await client.send({"op": "subscribe", "topic": "/fibonacci/result"})
        await client.frames_before_barrier()
        await _ros1_send_goal(client, "to-cancel", 40)
        await client.next_publish("/fibonacci/feedback")
        await client.send({"op": "publish", "topic": "/fibonacci/cancel", "msg": {"id": "to-cancel"}})
        result = await client.next_publish("/fibonacci/result")
    assert result["msg"]["status"]["status"] == 2
    assert 3 <= len(result["msg"]["result"]["sequence"]) < 41


async def test_ros1_cancel_with_empty_id_and_zero_stamp_cancels_all(sim_ros1: SimulatedRobot) -> None:
    """An empty GoalID cancels every goal: the running one is preempted."""
    async with await RawClient.open(sim_ros1.url) as client:
        await _ros1_send_goal(client, "a", 40)
        await sim_ros1.wait_for(lambda w: "a" in w.goals and w.goals["a"].feedback_count >= 1)
        await client.send({"op": "publish", "topic": "/fibonacci/cancel", "msg": {}})
        await sim_ros1.wait_for(lambda w: w.goals["a"].finished)
    assert sim_ros1.world.goals["a"].status == 2


async def test_ros1_status_is_published_periodically_with_ros1_codes(sim_ros1: SimulatedRobot) -> None:
    """/fibonacci/status arrives without any goal (actionlib's 5 Hz), then lists a goal as ACTIVE (1)."""
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "subscribe", "topic": "/fibonacci/status"})
        first = await client.next_publish("/fibonacci/status")
        await _ros1_send_goal(client, "watched", 40)
        while True:
            status = await client.next_publish("/fibonacci/status")
            states = {s["goal_id"]["id"]: s["status"] for s in status["msg"]["status_list"]}
            if states.get("watched") == 1:
                break
    assert first["msg"]["status_list"] == [] or all("goal_id" in s for s in first["msg"]["status_list"])


async def test_ros1_action_servers_names_fibonacci_several_times(sim_ros1: SimulatedRobot) -> None:
    """rosapi 0.11.17 quirk: a namespace is repeated for each later topic until another namespace starts."""
    async with await RawClient.open(sim_ros1.url) as client:
        servers = await client.values("/rosapi/action_servers")
    assert set(servers["action_servers"]) == {"/fibonacci"}
    assert len(servers["action_servers"]) > 1


async def test_humble_in_order_connection_blocks_behind_a_slow_service(sim_humble: SimulatedRobot) -> None:
    """Humble defaults: a call sent after /slow_service on the same socket is answered after it."""
    async with await RawClient.open(sim_humble.url) as client:
        await client.send({"op": "call_service", "id": "slow", "service": "/slow_service"})
        await client.send({"op": "call_service", "id": "fast", "service": "/rosapi/get_time"})
        first = await client.recv()
        second = await client.recv()
    assert [first["id"], second["id"]] == ["slow", "fast"]


async def test_jazzy_answers_a_quick_call_while_a_slow_one_runs(sim_ros2: SimulatedRobot) -> None:
    """Jazzy runs calls in their own threads: the quick reply overtakes the slow one on the same socket."""
    async with await RawClient.open(sim_ros2.url) as client:
        await client.send({"op": "call_service", "id": "slow", "service": "/slow_service"})
        await client.send({"op": "call_service", "id": "fast", "service": "/rosapi/get_time"})
        first = await client.recv()
        second = await client.recv()
    assert [first["id"], second["id"]] == ["fast", "slow"]


async def test_humble_slow_service_on_one_connection_does_not_block_another(
    sim_humble: SimulatedRobot,
) -> None:
    """The ordering is per connection: a second socket is answered while the first waits."""
    async with await RawClient.open(sim_humble.url) as busy, await RawClient.open(sim_humble.url) as free:
        await busy.send({"op": "call_service", "id": "slow", "service": "/slow_service"})
        assert "time" in await free.values("/rosapi/get_time")
        assert sim_humble.world.service_calls.get("/slow_service") == 1
        assert (await busy.reply("slow"))["result"] is True


async def test_humble_cancel_on_the_goals_own_connection_waits_until_the_goal_ends(make_sim: MakeSim) -> None:
    """In-order: the cancel queued behind the goal is read only after the goal finished (roslibjs#716)."""
    robot = await make_sim(dialect="ros2", in_order=True, action_step=0.02)
    async with await RawClient.open(robot.url) as client:
        await client.send(goal_op("blocking", 10, feedback=False))
        await client.send({"op": "cancel_action_goal", "id": "blocking", "action": "/fibonacci"})
        result = await client.reply("blocking", op="action_result")
    assert result["status"] == 4
    assert result["values"]["sequence"][-1] == 55


async def test_ros_version_reports_the_modelled_distro(make_sim: MakeSim) -> None:
    """get_ros_version says jazzy by default and humble with in_order; ROS 1 has no such service."""
    jazzy = await make_sim(dialect="ros2")
    humble = await make_sim(dialect="ros2", in_order=True)
    noetic = await make_sim(dialect="ros1")
    answers = []
    for robot in (jazzy, humble):
        async with await RawClient.open(robot.url) as client:
            answers.append(await client.values("/rosapi/get_ros_version"))
    async with await RawClient.open(noetic.url) as client:
        missing = await client.call("/rosapi/get_ros_version")
    assert answers == [{"version": 2, "distro": "jazzy"}, {"version": 2, "distro": "humble"}]
    assert missing["values"] == "Service /rosapi/get_ros_version does not exist"


async def test_goals_keep_running_after_their_client_disconnects(sim_ros2: SimulatedRobot) -> None:
    """No cleanup of goals on disconnect: the goal still finishes."""
    client = await RawClient.open(sim_ros2.url)
    await client.send(goal_op("orphan", 4, feedback=False))
    await sim_ros2.wait_for(lambda w: "orphan" in w.goals)
    await client.close()
    await sim_ros2.wait_for(lambda w: w.goals["orphan"].finished)
    assert sim_ros2.world.goals["orphan"].status == 4


async def test_ros1_cancel_with_a_stamp_cancels_goals_stamped_at_or_before_it(
    sim_ros1: SimulatedRobot,
) -> None:
    """A GoalID with an empty id and a stamp preempts goals stamped no later than it."""
    goal = {"goal_id": {"id": "stamped", "stamp": {"secs": 1000, "nsecs": 0}}, "goal": {"order": 40}}
    async with await RawClient.open(sim_ros1.url) as client:
        await client.send({"op": "publish", "topic": "/fibonacci/goal", "msg": goal})
        await sim_ros1.wait_for(lambda w: "stamped" in w.goals and w.goals["stamped"].feedback_count >= 1)
        await client.send(
            {"op": "publish", "topic": "/fibonacci/cancel", "msg": {"stamp": {"secs": 999, "nsecs": 0}}}
        )
        await client.frames_before_barrier()
        assert not sim_ros1.world.goals["stamped"].cancel_requested
        await client.send(
            {"op": "publish", "topic": "/fibonacci/cancel", "msg": {"stamp": {"secs": 1000, "nsecs": 0}}}
        )
        await sim_ros1.wait_for(lambda w: w.goals["stamped"].finished)
    assert sim_ros1.world.goals["stamped"].status == 2


async def test_ros1_a_new_goal_preempts_the_running_one(sim_ros1: SimulatedRobot) -> None:
    """SimpleActionServer runs one goal at a time: a newer goal preempts the running goal, then runs."""
    async with await RawClient.open(sim_ros1.url) as client:
        await _ros1_send_goal(client, "first", 40)
        await sim_ros1.wait_for(lambda w: "first" in w.goals and w.goals["first"].feedback_count >= 1)
        await _ros1_send_goal(client, "second", 3)
        await sim_ros1.wait_for(lambda w: "second" in w.goals and w.goals["second"].finished)
    assert sim_ros1.world.goals["first"].status == 2
    assert sim_ros1.world.goals["second"].status == 3


async def test_ros2_hidden_send_goal_service_is_listed_but_rosbridge_cannot_load_its_type(
    sim_ros2: SimulatedRobot,
) -> None:
    """As on a real bridge: *_SendGoal does not import as a service type; the call fails with that text."""
    async with await RawClient.open(sim_ros2.url) as client:
        node = await client.values("/rosapi/node_details", {"node": "/fibonacci_server"})
        reply = await client.call("/fibonacci/_action/send_goal", {"goal": {"order": 3}})
        unknown = await client.values(
            "/fibonacci/_action/cancel_goal", {"goal_info": {"goal_id": {"uuid": [9] * 16}}}
        )
    assert "/fibonacci/_action/send_goal" in node["services"]
    assert reply["result"] is False
    assert "Fibonacci_SendGoal" in reply["values"]
    assert unknown["return_code"] == 2  # ERROR_UNKNOWN_GOAL_ID


async def test_humble_client_leaving_during_a_blocking_call_is_cleaned_up_at_once(make_sim: MakeSim) -> None:
    """The socket's close is noticed while the in-order call still runs (like Tornado's on_close)."""
    robot = await make_sim(dialect="ros2", in_order=True, slow_service_seconds=30.0)
    client = await RawClient.open(robot.url)
    await client.send({"op": "subscribe", "topic": "/chatter"})
    await client.next_publish("/chatter")
    await client.send({"op": "call_service", "id": "stuck", "service": "/slow_service"})
    await robot.wait_for(lambda w: w.service_calls.get("/slow_service") == 1)
    await client.close()
    await robot.wait_for(lambda w: robot.connection_count == 0)
    assert "/rosbridge_websocket" not in robot.graph.subscribers_of("/chatter")


async def test_stop_does_not_wait_for_a_call_blocking_an_in_order_connection(make_sim: MakeSim) -> None:
    """stop() returns promptly even while a Humble connection sits inside a 30 s service call."""
    robot = await make_sim(dialect="ros2", in_order=True, slow_service_seconds=30.0)
    client = await RawClient.open(robot.url)
    await client.send({"op": "call_service", "id": "stuck", "service": "/slow_service"})
    await robot.wait_for(lambda w: w.service_calls.get("/slow_service") == 1)
    await asyncio.wait_for(robot.stop(), 5)
    await client.ws.wait_closed()
    assert not robot.running


async def test_goal_records_count_each_feedback_once(sim: SimulatedRobot) -> None:
    """world.goals[id].feedback_count equals the feedback messages of the goal (order 5: four)."""
    async with await RawClient.open(sim.url) as client:
        if sim.dialect == "ros2":
            await client.send(goal_op("counted", 5, feedback=False))
        else:
            await _ros1_send_goal(client, "counted", 5)
        await sim.wait_for(lambda w: "counted" in w.goals and w.goals["counted"].finished)
    assert sim.world.goals["counted"].feedback_count == 4


async def _host_action(host: RawClient, name: str = "/hosted") -> None:
    await host.send({"op": "advertise_action", "action": name, "type": FIBONACCI})
    await host.frames_before_barrier()


async def test_a_client_hosted_action_gets_goals_and_its_feedback_and_result_reach_the_caller(
    sim_ros2: SimulatedRobot,
) -> None:
    """advertise_action: goals arrive as send_action_goal (action_goal id); feedback and result flow back."""
    async with await RawClient.open(sim_ros2.url) as host, await RawClient.open(sim_ros2.url) as caller:
        await _host_action(host)
        servers = await caller.values("/rosapi/action_servers")
        await caller.send({**goal_op("to-host", 7), "action": "/hosted"})
        goal = await host.recv_until(lambda f: f.get("op") == "send_action_goal")
        await host.send(
            {"op": "action_feedback", "id": goal["id"], "action": "/hosted", "values": {"sequence": [0, 1]}}
        )
        feedback = await caller.reply("to-host", op="action_feedback")
        await host.send(
            {
                "op": "action_result",
                "id": goal["id"],
                "action": "/hosted",
                "status": 4,
                "result": True,
                "values": {"sequence": [0, 1, 1]},
            }
        )
        result = await caller.reply("to-host", op="action_result")
    assert "/hosted" in servers["action_servers"]
    assert goal["id"].startswith("action_goal:/hosted:")
    assert goal["args"] == {"order": 7}
    assert goal["action_type"] == FIBONACCI
    assert feedback["values"] == {"sequence": [0, 1]}
    assert (result["status"], result["values"]) == (4, {"sequence": [0, 1, 1]})


async def test_cancel_of_a_hosted_goal_is_forwarded_and_the_host_decides_the_end(
    sim_ros2: SimulatedRobot,
) -> None:
    """A cancel reaches the host as cancel_action_goal; the goal ends when the host answers status 5."""
    async with await RawClient.open(sim_ros2.url) as host, await RawClient.open(sim_ros2.url) as caller:
        await _host_action(host)
        await caller.send({**goal_op("cancel-me", 7), "action": "/hosted"})
        goal = await host.recv_until(lambda f: f.get("op") == "send_action_goal")
        await caller.send({"op": "cancel_action_goal", "id": "cancel-me", "action": "/hosted"})
        cancel = await host.recv_until(lambda f: f.get("op") == "cancel_action_goal")
        await host.send(
            {"op": "action_result", "id": goal["id"], "action": "/hosted", "status": 5, "result": True}
        )
        result = await caller.reply("cancel-me", op="action_result")
    assert cancel == {"op": "cancel_action_goal", "id": goal["id"], "action": "/hosted"}
    assert result["status"] == 5


async def test_unadvertise_action_aborts_goals_in_flight(sim_ros2: SimulatedRobot) -> None:
    """Goals of an unadvertised action end ABORTED (6); the action leaves the graph."""
    async with await RawClient.open(sim_ros2.url) as host, await RawClient.open(sim_ros2.url) as caller:
        await _host_action(host)
        await caller.send({**goal_op("dropped", 7), "action": "/hosted"})
        await host.recv_until(lambda f: f.get("op") == "send_action_goal")
        await host.send({"op": "unadvertise_action", "action": "/hosted"})
        result = await caller.reply("dropped", op="action_result")
        servers = await caller.values("/rosapi/action_servers")
    assert result["status"] == 6
    assert "/hosted" not in servers["action_servers"]


async def test_action_result_with_result_false_aborts_the_goal(sim_ros2: SimulatedRobot) -> None:
    """result false from the host means ABORTED whatever the status says."""
    async with await RawClient.open(sim_ros2.url) as host, await RawClient.open(sim_ros2.url) as caller:
        await _host_action(host)
        await caller.send({**goal_op("failed", 7), "action": "/hosted"})
        goal = await host.recv_until(lambda f: f.get("op") == "send_action_goal")
        await host.send(
            {"op": "action_result", "id": goal["id"], "action": "/hosted", "status": 4, "result": False}
        )
        result = await caller.reply("failed", op="action_result")
    assert result["status"] == 6
    assert result["result"] is True
