"""The console's read-only view as an MCP App: listed, bound to show_console, and rendered in Chromium.

The host side is a small harness page: it puts the ``ui://`` page in a sandboxed iframe, answers
``ui/initialize`` and forwards the view's ``tools/call`` to the real MCP session (as a host does).
"""

from __future__ import annotations

import json
from typing import Any

from console_harness import CHROMIUM_ARGS, served_console, text_of

try:
    from playwright.async_api import async_playwright, expect
except ImportError:  # no browser group: need_chromium() skips the browser tests, saying how to install it
    async_playwright = expect = None  # type: ignore[assignment]

from rosbridge_mcp_server.sim import SimulatedRobot

APP_URI = "ui://rosbridge/console.html"
APP_MIME = "text/html;profile=mcp-app"
WAIT_MS = 30_000

HOST_PAGE = """<!doctype html><html><body>
<iframe id="app" sandbox="allow-scripts" style="width:900px;height:800px"></iframe>
<script>
const frame = document.getElementById("app");
window.addEventListener("message", async (event) => {
  if (event.source !== frame.contentWindow) return;
  const message = event.data;
  if (!message || !message.method || message.id === undefined) return;
  let answer;
  if (message.method === "ui/initialize") {
    const hostInfo = { name: "harness", version: "0" };
    answer = { result: { protocolVersion: message.params.protocolVersion, hostInfo,
                         hostCapabilities: { serverTools: {} }, hostContext: {} } };
  } else {
    answer = JSON.parse(await window.hostCall(message.method, JSON.stringify(message.params)));
  }
  frame.contentWindow.postMessage({ jsonrpc: "2.0", id: message.id, ...answer }, "*");
});
</script></body></html>"""


async def test_the_app_is_listed_bound_to_its_tool_and_renders_status_audit_and_camera(
    sim_ros2: SimulatedRobot,
) -> None:
    """resources/list has the ui:// page; in a browser it shows the connection, an acting call and a frame."""
    from console_harness import need_chromium

    executable = need_chromium()
    async with served_console(sim_ros2.url) as console:
        resources = await console.mcp.list_resources()
        [listed] = [r for r in resources.resources if str(r.uri) == APP_URI]
        assert listed.mime_type == APP_MIME
        tools = {tool.name: tool for tool in (await console.mcp.list_tools()).tools}
        assert tools["show_console"].meta == {"ui": {"resourceUri": APP_URI}}
        assert tools["show_console"].annotations is not None
        assert tools["show_console"].annotations.read_only_hint
        read = await console.mcp.read_resource(APP_URI)
        html = read.contents[0].text  # type: ignore[union-attr]
        assert "E-STOP" in html  # named, to say where it is; the view has no such button
        assert "/api/estop" not in html

        moved = await console.call(
            "publish_topic",
            {"topic": "/turtle1/cmd_vel", "message_type": "geometry_msgs/msg/Twist", "message": {}},
        )
        assert not moved.is_error, text_of(moved)

        async def host_call(method: str, params: str) -> str:
            arguments: dict[str, Any] = json.loads(params)
            if method != "tools/call":
                return json.dumps({"error": {"code": -32601, "message": f"{method} is not served here"}})
            result = await console.call(arguments["name"], arguments.get("arguments") or {})
            return json.dumps({"result": result.model_dump(mode="json", by_alias=True, exclude_none=True)})

        async with async_playwright() as playwright:
            browser = await playwright.chromium.launch(executable_path=executable, args=CHROMIUM_ARGS)
            try:
                page = await browser.new_page()
                await page.expose_function("hostCall", host_call)
                await page.set_content(HOST_PAGE)
                await page.evaluate("html => { document.getElementById('app').srcdoc = html; }", html)
                app = page.frame_locator("#app")
                await expect(app.locator("#robots")).to_contain_text("connected", timeout=WAIT_MS)
                await expect(app.locator("#audit li").first).to_contain_text(
                    "/turtle1/cmd_vel", timeout=WAIT_MS
                )
                await app.get_by_role("button", name="Show").click()
                await expect(app.locator("#camera")).to_be_visible(timeout=WAIT_MS)
                [view] = [frame for frame in page.frames if frame is not page.main_frame]
                await view.wait_for_function(
                    "() => document.getElementById('camera').naturalWidth > 0", timeout=WAIT_MS
                )
                assert await app.get_by_role("button", name="E-STOP").count() == 0
                assert await app.get_by_role("button", name="Approve").count() == 0
            finally:
                await browser.close()


async def test_show_console_answers_the_model_in_a_few_lines(sim_ros2: SimulatedRobot) -> None:
    """The tool's text says the connection and the last acting calls; its structured content is the view's."""
    async with served_console(sim_ros2.url) as console:
        result = await console.call("show_console", {})
        assert not result.is_error
        assert "connected (ROS 2" in text_of(result)
        assert "No acting call yet." in text_of(result)
        assert result.structured_content is not None
        assert result.structured_content["estop"] == {"latched": False, "by": None}


async def test_show_console_refuses_an_argument_it_does_not_take(sim_ros2: SimulatedRobot) -> None:
    """show_console takes no arguments: an unknown one is refused by name, like any tool's."""
    async with served_console(sim_ros2.url) as console:
        result = await console.call("show_console", {"verbose": True})
        assert result.is_error
        assert "unknown argument 'verbose'" in text_of(result)
        assert "no arguments" in text_of(result)
