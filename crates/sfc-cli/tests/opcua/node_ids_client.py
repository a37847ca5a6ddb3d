"""Browses the whole address space `sfc run --opcua` serves and checks every node of the run's
namespace against the node ids docs/runtime.md ("Node ids") documents, then reads every node by
its documented id.

Usage: node_ids_client.py URL POU

The documented id of a node is computed here from its place in the browse tree alone (this file
is an independent reading of the documentation, not of the server's code):

- the program object: `POU`; its folders and objects: `POU/<browse name>` (Inputs, Outputs,
  Locals, Globals, Chart, Runtime);
- a variable in Inputs/Outputs/Locals/Globals: `POU.<name>`;
- a property (HasProperty) of a node: `<that node's id>/<property name>`;
- a component of Chart, of a function block instance's chart or of Runtime, and the Steps,
  Transitions and Actions folders: `<parent id>/<browse name>`;
- a function block instance's chart under Chart: `POU/Chart/<instance path>`;
- a step, transition or action: `POU/Steps/<qualified name>` (`Transitions`, `Actions`), the
  qualified name being the instance path, a dot and the browse name inside a function block
  instance's chart, the browse name in the program's own chart; their X, T, Guard, Q, A:
  `<its id>/<name>`;
- an ObjectType of the run: `type:<name>`; its components `type:<name>/<component>`.

Prints one JSON object: how many nodes were checked, and the mismatches and failed reads.
"""

import asyncio
import json
import sys

from asyncua import Client, ua

NS_URI = "urn:sfc:run"
FOLDERS = ("Inputs", "Outputs", "Locals", "Globals")


async def children(node, ref=ua.ObjectIds.HierarchicalReferences):
    """Forward hierarchical children with their reference type id."""
    refs = await node.get_references(refs=ref, direction=ua.BrowseDirection.Forward, includesubtypes=True)
    return [(r.ReferenceTypeId.Identifier, r.NodeId, r.BrowseName.Name) for r in refs]


async def main(url, pou):
    checked, wrong, unread = 0, [], []
    seen = set()
    async with Client(url) as c:
        ns = await c.get_namespace_index(NS_URI)

        async def check(node_id, documented, kind):
            nonlocal checked
            checked += 1
            got = node_id.to_string()
            want = f"ns={ns};s={documented}"
            if got != want:
                wrong.append({"documented": want, "server": got, "kind": kind})
            # Read it back by the documented id: its browse name, and a variable's value.
            try:
                n = c.get_node(want)
                await n.read_browse_name()
                if await n.read_node_class() == ua.NodeClass.Variable:
                    dv = await n.read_data_value(raise_on_bad_status=False)
                    if dv.StatusCode.is_bad() and dv.StatusCode.name != "BadWaitingForInitialData":
                        unread.append({"id": want, "status": dv.StatusCode.name})
            except Exception as e:  # noqa: BLE001 - every failure is reported
                unread.append({"id": want, "error": str(e)})

        async def walk(node, documented, place):
            """`node` has the documented id `documented`; `place` says what it is."""
            key = node.nodeid.to_string()
            if key in seen:
                return
            seen.add(key)
            await check(node.nodeid, documented, place["kind"])
            for ref, child_id, name in await children(node):
                if child_id.NamespaceIndex != ns:
                    continue
                child = c.get_node(child_id)
                if ref == ua.ObjectIds.HasProperty:
                    await walk(child, f"{documented}/{name}", {"kind": "property"})
                elif place["kind"] == "program" and name in FOLDERS:
                    await walk(child, f"{pou}/{name}", {"kind": "section"})
                elif place["kind"] == "section":
                    await walk(child, f"{pou}.{name}", {"kind": "variable"})
                elif place["kind"] == "program" and name == "Chart":
                    await walk(child, f"{pou}/Chart", {"kind": "chart", "path": ""})
                elif place["kind"] == "program":
                    await walk(child, f"{pou}/{name}", {"kind": "object"})
                elif place["kind"] == "chart" and name in ("Steps", "Transitions", "Actions"):
                    await walk(child, f"{documented}/{name}", {"kind": "list", "list": name, "path": place["path"]})
                elif place["kind"] == "chart" and name in ("LastError", "LastErrorCode", "LastErrorStep", "ErrorCount"):
                    await walk(child, f"{documented}/{name}", {"kind": "error"})
                elif place["kind"] == "chart":
                    # A function block instance's chart: its browse name is its instance path.
                    await walk(child, f"{pou}/Chart/{name}", {"kind": "chart", "path": name})
                elif place["kind"] == "list":
                    qualified = f"{place['path']}.{name}" if place["path"] else name
                    await walk(child, f"{pou}/{place['list']}/{qualified}", {"kind": "element"})
                else:
                    await walk(child, f"{documented}/{name}", {"kind": "member"})

        root = await c.nodes.objects.get_child([f"{ns}:{pou}"])
        await walk(root, pou, {"kind": "program"})
        # The ObjectTypes of the run's namespace, under BaseObjectType.
        base = c.get_node(ua.ObjectIds.BaseObjectType)
        types = 0
        for ref, type_id, name in await children(base, ua.ObjectIds.HasSubtype):
            if type_id.NamespaceIndex != ns:
                continue
            types += 1
            t = c.get_node(type_id)
            await check(type_id, f"type:{name}", "type")
            for _, member_id, member in await children(t, ua.ObjectIds.HasComponent):
                if member_id.NamespaceIndex == ns:
                    await check(member_id, f"type:{name}/{member}", "type member")
    print(json.dumps({"checked": checked, "types": types, "wrong": wrong[:40], "wrong_count": len(wrong),
                      "unread": unread[:40], "unread_count": len(unread)}))


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], sys.argv[2]))
