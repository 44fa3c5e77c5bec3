#!/usr/bin/env bash
# Streamable HTTP smoke: the demo server with a bearer token on a free loopback port, then the TypeScript MCP
# SDK's client (smoke.mjs: list every tool, call each) and MCP Inspector's CLI (--transport http) against it.
# The tools and their examples come from the catalogue and README.md (tools.py), never from a list kept here.
# Needs node/npm; installs @modelcontextprotocol/sdk into a temporary directory. Exit 0 when both pass.
set -euo pipefail
cd "$(dirname "$0")/../.."
work=$(mktemp -d)
token="smoke-$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')"
server_pid=""
cleanup() {
    [[ -n "$server_pid" ]] && kill "$server_pid" 2>/dev/null && wait "$server_pid" 2>/dev/null
    rm -rf "$work"
}
trap cleanup EXIT

tools_json=$(.venv/bin/python scripts/http-smoke/tools.py)

ROSBRIDGE_MCP_AUTH_TOKENS="smoke $token" .venv/bin/rosbridge-mcp-server --demo --transport http \
    --bind 127.0.0.1:0 --record-dir "$work/recordings" 2>"$work/server.log" &
server_pid=$!
for _ in $(seq 300); do
    url=$(grep -o 'serving MCP on [^ ]*' "$work/server.log" | head -1 | cut -d' ' -f4 || true)
    [[ -n "$url" ]] && break
    kill -0 "$server_pid" 2>/dev/null || { cat "$work/server.log"; exit 1; }
    sleep 0.1
done
[[ -n "$url" ]] || { echo "the server did not say where it listens"; cat "$work/server.log"; exit 1; }
echo "server: $url"

(cd "$work" && npm init -y >/dev/null && npm install --silent --no-audit --no-fund @modelcontextprotocol/sdk@1 >/dev/null)
cp scripts/http-smoke/smoke.mjs "$work/"
(cd "$work" && MCP_URL="$url" MCP_TOKEN="$token" SMOKE_TOOLS="$tools_json" timeout 300 node smoke.mjs)

tools=$(timeout 300 npx -y @modelcontextprotocol/inspector@2.12.0 --cli "$url" --transport http \
    --header "Authorization: Bearer $token" --method tools/list)
listed=$(grep -c '"name": ' <<<"$tools" || true)
for name in $(.venv/bin/python scripts/http-smoke/tools.py --names); do
    grep -q "\"$name\"" <<<"$tools" || { echo "inspector: tools/list lacks $name"; exit 1; }
done
answer=$(timeout 300 npx -y @modelcontextprotocol/inspector@2.12.0 --cli "$url" --transport http \
    --header "Authorization: Bearer $token" --method tools/call --tool-name list_topics)
grep -q '/turtle1/pose' <<<"$answer" || { echo "inspector: list_topics did not show /turtle1/pose"; exit 1; }
echo "inspector (--transport http): tools/list answered ($listed names), tools/call list_topics sees /turtle1/pose"
if grep -q "$token" "$work/server.log"; then echo "the token appears in the server's log"; exit 1; fi
