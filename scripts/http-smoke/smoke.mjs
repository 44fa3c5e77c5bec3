// The TypeScript MCP SDK's Streamable HTTP client against a running server: list every tool, call each one.
//
//   MCP_URL=http://127.0.0.1:8765/mcp MCP_TOKEN=... SMOKE_TOOLS="$(python tools.py)" node smoke.mjs
//
// Run from a directory where `npm install @modelcontextprotocol/sdk` was done (scripts/http-smoke/run.sh does
// that in a temporary directory). SMOKE_TOOLS is every tool of the catalogue with its README example
// (tools.py): tools/list must list exactly those, and each is called with its example, or with DEMO's where
// the README's does not suit the demo robot or takes long. A tool of OTHER_WORLDS needs a robot the demo's
// default world is not (Nav2, an arm): it only has to answer (an error result counts: it was callable). Exit 1
// when a tool is missing or unknown, when any other tool answers with an error, or when a call gets no result.
import { Client } from "@modelcontextprotocol/sdk/client/index.js";
import { StreamableHTTPClientTransport } from "@modelcontextprotocol/sdk/client/streamableHttp.js";

const EXAMPLES = JSON.parse(process.env.SMOKE_TOOLS ?? "{}");
const DEMO = {
  plot_topic: { series: ["/turtle1/pose x theta"], duration: 1 },
  // read_recording's README example reads run1.mcap.
  record: { topics: ["/turtle1/pose"], duration: 1, name: "run1" },
};
const OTHER_WORLDS = new Set(["navigate_to", "move_arm", "move_gripper"]);

const url = new URL(process.env.MCP_URL ?? "http://127.0.0.1:8765/mcp");
const headers = process.env.MCP_TOKEN ? { Authorization: `Bearer ${process.env.MCP_TOKEN}` } : {};
const transport = new StreamableHTTPClientTransport(url, { requestInit: { headers } });
const client = new Client({ name: "http-smoke", version: "0" });
await client.connect(transport);
const { tools } = await client.listTools();
const listed = tools.map((tool) => tool.name);
const missing = Object.keys(EXAMPLES).filter((name) => !listed.includes(name));
const unknown = listed.filter((name) => !(name in EXAMPLES));
let failed = missing.length + unknown.length + (listed.length ? 0 : 1);
if (missing.length) console.log(`FAIL not listed: ${missing.join(", ")}`);
if (unknown.length) console.log(`FAIL listed but not in the catalogue: ${unknown.join(", ")}`);
for (const tool of tools) {
  const must = tool.name in EXAMPLES && !OTHER_WORLDS.has(tool.name);
  try {
    const result = await client.callTool({ name: tool.name, arguments: DEMO[tool.name] ?? EXAMPLES[tool.name] ?? {} });
    const text = (result.content ?? []).filter((c) => c.type === "text").map((c) => c.text).join(" ");
    const ok = !(must && result.isError);
    if (!ok) failed += 1;
    console.log(`${ok ? "ok  " : "FAIL"} ${tool.name}${result.isError ? " (error result)" : ""}: ${text.slice(0, 90)}`);
  } catch (error) {
    failed += 1;
    console.log(`FAIL ${tool.name}: no result: ${error}`);
  }
}
console.log(`${tools.length} tools listed (the catalogue's), ${failed ? failed + " failure(s)" : "each answered as expected"}`);
await client.close();
process.exit(failed ? 1 : 0);
