#!/usr/bin/env bash
# Bump the version, run the checks, commit and tag. Pushing the tag starts the release workflow.
#   scripts/release.sh patch|minor|major|X.Y.Z
set -euo pipefail
cd "$(dirname "$0")/.."

bump=${1:-}
if [[ -z "$bump" ]]; then
    echo "usage: scripts/release.sh patch|minor|major|X.Y.Z" >&2
    exit 2
fi
if [[ -n "$(git status --porcelain)" ]]; then
    echo "the work tree has uncommitted changes; commit or stash them first" >&2
    exit 1
fi

if [[ "$bump" =~ ^[0-9]+\.[0-9]+\.[0-9]+$ ]]; then
    uv version "$bump"
else
    uv version --bump "$bump"
fi
version=$(uv version --short)
# Keep the package's own __version__ in step with pyproject.toml.
sed -i.bak -E "s/^__version__ = \".*\"/__version__ = \"$version\"/" src/rosbridge_mcp_server/__init__.py
rm -f src/rosbridge_mcp_server/__init__.py.bak

bash .ci/run

git add pyproject.toml uv.lock src/rosbridge_mcp_server/__init__.py
git commit -m "Release $version"
git tag -a "v$version" -m "rosbridge-mcp-server $version"
echo "Tagged v$version. Push with: git push origin main v$version"
