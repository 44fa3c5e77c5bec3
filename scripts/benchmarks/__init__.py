"""Benchmark rosbridge-mcp-server against the raw rosbridge floor, every figure a ratio taken in one run.

    uv run python scripts/bench.py                       # against a simulated robot in its own process
    uv run python scripts/bench.py --url ws://robot:9090 # against any rosbridge (sim-only rows become n/a)
    uv run python scripts/bench.py --quick               # tiny counts, ~2 min (the smoke test)
    uv run python scripts/bench.py --only latency        # some items: latency, concurrency, throughput, ...
    uv run python scripts/bench.py --json bench-$(date -u +%Y%m%d-%H%M).json

The machines we run on are shared and noisy, so nothing is compared with a number from another run: each
subject is measured next to its reference in the same run, in interleaved blocks (A B C A B C ..., with the
order rotated every round) after warm-up rounds, and reported as median, p90 and the ratio of the medians.

What is measured:

1. the floor: ``call_service /rosapi/topics`` over one raw ``websockets`` connection;
2. the same call through our ``RosbridgeClient`` and through roslibpy;
3. ``list_topics`` and ``publish_service /add_two_ints`` through a real MCP stdio session with the console
   script, next to the same SDK's cost for a tool that does nothing (``servers/bare_server.py``),
   and, for comparison, all three again on the MCP SDK's own stdio transport instead of ours;
4. 100 tool calls at once in one session against a 50 ms service, against 100 in a row;
5. 1 000 messages of the 1 kHz topic: how many were lost; a camera frame as an MCP image; a PNG
   decompression bomb (13000² at 16 bits in ~330 kB) refused by ``get_image``, with the server's peak RSS
   growth while it is;
6. spawn → ``initialize`` → ``tools/list``, against a bare ``MCPServer`` started the same way;
7. RSS after startup and its growth over 10 000 tool calls, against the same bare server;
8. the graph tools against the raw rosapi round trips each needs (``--only graph``; meant for real bridges).
9. the watch tools: ``get_image`` on a live 640×480 and 1920×1080 rgb8 camera and
   ``subscribe_topic`` count 1 on a live topic, each against a raw subscribe → first message → unsubscribe
   started at the same point of the publisher's cycle; a 10 Hz × 5 s ``publish_topic`` stream as the robot
   receives it; the size of ``tools/list`` with every tool and with the original eight.
10. Streamable HTTP (``--only http``): ``list_topics`` over HTTP with a bearer token against the same call
    over stdio, interleaved, and 100 HTTP sessions opened at once (initialize + one call each), all working.
11. the picture tools (``--only view``): ``view_map`` on a 2000×2000 ``/map`` against a raw socket's receipt
    of the same message (subscribe → every fragment → parsed → unsubscribe), ``view_scan`` against a raw first
    scan (phase-locked to the 5 Hz laser), and the PNG sizes of their pictures and of a ``plot_topic`` chart.
12. every graph tool on a simulated Nav2 robot (``--only nav2``; ~36 nodes, ~400 services, 1,000+
    parameters), the server alone (JSON-RPC lines), against the raw calls its answer needs, with the size of
    each answer's text and structured content; ``get_node_info`` also on the same world behaving like
    rosbridge-server-rs (row 12k: one round trip, no node list first).
13. ``diagnose`` (``--only diagnose``) on the simulated Nav2 world, healthy and with two faults, through the
    console script (p50 against its 1.5 s target); and the log ring under 10,000 ``/rosout`` lines a second
    for 10 s from a simulated robot in this process: lines received, kept, dropped, and the RSS along the way.
14. recording (``--only recording``): ``record`` of a Nav2-like load (scan, odom, tf, a 640×480 camera)
    against what a raw subscriber received, ``list_topics`` while it records against idle, and the summary
    time of a large recording (from the MCAP index).
15. the server alone over the floor (``--only edge``; issue 26, item 8): every tool row on the simulated robot
    by JSON-RPC lines against the rosbridge requests it makes, p50/p90 and "floor + X ms"; with ``--url``
    ``list_topics`` and ``get_node_info`` on that bridge; with ``--ros-mcp PYTHON`` ros-mcp beside it.
16. stops and reconnects (``--only stops``; issue 26: what tests used to time with wall clocks), each on
    simulated robots of its own: ``stop_robot`` with a velocity stream running (to its answer, to the zero a
    raw subscriber receives, non-zero commands after the answer) and with a ``navigate_to`` goal running on
    the Nav2 world (to its answer, to ``/odom`` standing still); the bridge killed and restarted on its port
    (to ``list_topics`` succeeding, and no command replayed).
17. MCP tasks (``--only tasks``): ``tasks/get`` on a running task (a ``subscribe_topic`` with a duration,
    started by a 2026-07-28 client advertising the tasks extension) against the no-op tool, interleaved.
18. the arm (``--only arm``): joint limits and forward kinematics at 101 points of a 7-joint goal's path
    (p50 ≤ 5 ms), ``view_arm`` on the simulated arm (``--world arm``) and its text for a 7-joint arm with a
    gripper (≤ 8,000 characters).

The package: ``harness`` (what every item shares), one module per item, ``run`` (the order, the table, the
command line), ``internals`` (the only module that imports the product's internals, and why), ``servers/``
(the reference servers it starts) and ``decompose`` (a profiling aid, run on its own).

The table goes to stdout (Markdown, so it can be pasted into docs/performance.md), progress to stderr.
The exit status is 0 when every measurement ran, whatever the figures; 1 when something errored.
"""

__all__: list[str] = []
