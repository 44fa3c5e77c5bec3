// The TypeScript MCP SDK's Streamable HTTP client against a running server: list every tool, call each one.
//
//   MCP_URL=http://127.0.0.1:8765/mcp MCP_TOKEN=... node smoke.mjs
//
// Run from a directory where `npm install @modelcontextprotocol/sdk` was done (scripts/http-smoke/run.sh does
// that in a temporary directory). Tools are called with arguments that suit the demo robot; a tool this script
// does not know is called with {} and only has to answer (an error result counts: it was callable). Exit 1
// when a known tool fails or any call gets no result.
import { Client } from "@modelcontextprotocol/sdk/client/index.js";
import { StreamableHTTPClientTransport } from "@modelcontextprotocol/sdk/client/streamableHttp.js";

const TWIST = { linear: { x: 0.1 }, angular: { z: 0.1 } };
const EXAMPLES = {
  list_topics: {},
  get_topic_info: { topic: "/turtle1/pose" },
  publish_topic: { topic: "/turtle1/cmd_vel", message_type: "geometry_msgs/msg/Twist", message: TWIST },
  list_services: {},
  publish_service: {
    service: "/add_two_ints",
    service_type: "example_interfaces/srv/AddTwoInts",
    request: { a: 2, b: 3 },
  },
  list_actions: {},
  publish_action: {
    action_name: "/fibonacci",
    action_type: "example_interfaces/action/Fibonacci",
    goal: { order: 3 },
    timeout: 30,
  },
  cancel_action: { action_name: "/fibonacci" },
  subscribe_topic: { topic: "/turtle1/pose" },
  get_image: { topic: "/camera/image_raw", max_size: 64 },
  describe_type: { type_name: "geometry_msgs/msg/Twist" },
  list_nodes: {},
  get_node_info: { node: "/turtlesim" },
  list_parameters: { node: "/turtlesim" },
  get_parameter: { name: "/turtlesim:background_r" },
  set_parameter: { name: "/turtlesim:background_r", value: 100 },
  get_transform: { target_frame: "odom", source_frame: "base_link" },
  read_logs: { level: "info" },
  diagnose: { focus: "tf" },
  view_map: { path_topic: "/plan", scan_topic: "/scan", max_size: 200 },
  view_scan: { max_size: 200 },
  plot_topic: { series: ["/turtle1/pose x theta"], duration: 1 },
  stop_robot: {},
};

const url = new URL(process.env.MCP_URL ?? "http://127.0.0.1:8765/mcp");
const headers = process.env.MCP_TOKEN ? { Authorization: `Bearer ${process.env.MCP_TOKEN}` } : {};
const transport = new StreamableHTTPClientTransport(url, { requestInit: { headers } });
const client = new Client({ name: "http-smoke", version: "0" });
await client.connect(transport);
const { tools } = await client.listTools();
let failed = 0;
for (const tool of tools) {
  const known = tool.name in EXAMPLES;
  try {
    const result = await client.callTool({ name: tool.name, arguments: EXAMPLES[tool.name] ?? {} });
    const text = (result.content ?? []).filter((c) => c.type === "text").map((c) => c.text).join(" ");
    const ok = !(known && result.isError);
    if (!ok) failed += 1;
    console.log(`${ok ? "ok  " : "FAIL"} ${tool.name}${result.isError ? " (error result)" : ""}: ${text.slice(0, 90)}`);
  } catch (error) {
    failed += 1;
    console.log(`FAIL ${tool.name}: no result: ${error}`);
  }
}
console.log(`${tools.length} tools listed, ${tools.length - failed} answered as expected`);
await client.close();
process.exit(failed ? 1 : 0);
