"""Lua bridge: the script compiles, the item encoding round-trips, and the real script — run by Lua 5.4
(lupa, from PyPI) with stand-ins for ArduPilot's bindings — sends exactly the commands the items encode.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings, strategies as st

from missions.emit import lua
from missions.errors import PlanError
from missions.emit.items import mavlink


def lua54():
    """A fresh Lua 5.4 (lupa, pinned in requirements.lock: the same interpreter on every machine) whose
    `print` lines are collected in the returned list."""
    from lupa.lua54 import LuaRuntime

    runtime, printed = LuaRuntime(), []
    runtime.globals().print = lambda *args: printed.append(" ".join(str(a) for a in args))
    return runtime, printed

param = st.one_of(st.none(), st.floats(-1e6, 1e6, allow_nan=False, width=32))
commands = st.builds(lua.BridgeCommand, st.sampled_from(lua.BRIDGE_COMMANDS), st.integers(100, 105),
                     st.tuples(param, param, param, param, param, param, param))


def same(a, b) -> bool:
    return all((x is None and y is None) or (x is not None and y is not None and x == pytest.approx(y))
               for x, y in zip(a, b))


@settings(max_examples=200, deadline=None)
@given(st.lists(commands, min_size=1, max_size=5))
def test_encode_decode_round_trip(cmds):
    items = [it for c in cmds for it in lua.encode(c)]
    assert all(it.command == mavlink.MAV_CMD_DO_SEND_SCRIPT_MESSAGE for it in items)
    assert all(0 <= int(it.param1) <= 0xFFFF and it.param1 == int(it.param1) for it in items)
    assert all(math.isfinite(v) for it in items for v in (it.param2, it.param3, it.param4))   # no NaN on the wire
    back = lua.decode(items)
    assert [(b.command, b.component) for b in back] == [(c.command, c.component) for c in cmds]
    for b, c in zip(back, cmds):
        assert same(b.params, c.params)


def test_items_per_command():
    c = lua.BridgeCommand("MAV_CMD_USER_1", 101, (1.0, None, None, None, None, None, None))
    assert len(lua.encode(c)) == 1
    c = lua.BridgeCommand("MAV_CMD_SET_CAMERA_MODE", 100, (0.0, 0.0, None, None, 3.0, None, 50.0))
    assert len(lua.encode(c)) == 3


def test_foreign_script_ids_are_ignored():
    other = lua.encode(lua.BridgeCommand("MAV_CMD_USER_2", 100, (None, 1.0, None, None, None, None, None)))[0]
    assert lua.decode([other.with_(param1=7.0)]) == []


def test_refuses_non_bridge_command_and_component():
    with pytest.raises(PlanError) as ei:
        lua.encode(lua.BridgeCommand("MAV_CMD_IMAGE_START_CAPTURE", 100, (None,) * 7))
    assert "MAV_CMD_USER_1" in ei.value.hint
    with pytest.raises(PlanError) as ei:
        lua.encode(lua.BridgeCommand("MAV_CMD_USER_1", 99, (None,) * 7))
    assert "CAMERA6" in ei.value.hint and "report" in ei.value.hint


def test_refuses_a_value_that_is_not_finite():
    with pytest.raises(PlanError, match="not finite") as ei:
        lua.encode(lua.BridgeCommand("MAV_CMD_USER_1", 101, (math.inf,) + (None,) * 6))
    assert "report" in ei.value.hint


def test_script_is_valid_lua():
    runtime, _ = lua54()
    syntax_error = runtime.eval("function(src) local _, err = load(src, 'bridge.lua'); return err end")
    assert syntax_error(lua.render_script("demo-plan")) is None
    assert syntax_error("x = = 1") is not None      # the check can fail


HARNESS = r"""
local items = {ITEMS}
local sent = {}
package.preload["MAVLink/mavlink_msgs"] = function()
  return {
    get_msgid = function(name) return ({HEARTBEAT = 0, COMMAND_ACK = 77})[name] end,
    encode = function(name, msg) return 76, msg end,
    decode = function(msg, map) return msg end,
  }
end
local inbox = { { {msgid = 0, sysid = 1, compid = KNOWN_COMP}, 2 } }
mavlink = {
  init = function(self, a, b) end,
  register_rx_msgid = function(self, id) end,
  receive_chan = function(self)
    local m = table.remove(inbox, 1)
    if m then return m[1], m[2] end
    return nil
  end,
  send_chan = function(self, chan, msgid, msg) table.insert(sent, {chan, msgid, msg}); return true end,
}
param = { get = function(self, name) return 7 end }
gcs = { send_text = function(self, sev, text) end }
function mission_receive()
  local it = table.remove(items, 1)
  if it then return 1000, it[1], it[2], it[3], it[4] end
  return nil
end
local update, period = dofile(SCRIPT)
assert(type(update) == "function" and period > 0)
update()
for _, s in ipairs(sent) do
  local m = s[3]
  local out = {s[1], s[2], m.target_system, m.target_component, m.command}
  for i = 1, 7 do
    local v = m["param" .. i]
    out[#out + 1] = (v ~= v) and "nan" or string.format("%.9g", v)
  end
  print(table.concat(out, " "))
end
"""


@settings(max_examples=25, deadline=None)
@given(st.lists(commands, min_size=1, max_size=4))
def test_real_script_sends_what_the_items_encode(tmp_path_factory, cmds):
    tmp = tmp_path_factory.mktemp("lua")
    script = tmp / "bridge.lua"
    script.write_text(lua.render_script("fuzz"))
    items = [it for c in cmds for it in lua.encode(c)]
    rows = ", ".join(f"{{{int(it.param1)}, {it.param2!r}, {it.param3!r}, {it.param4!r}}}" for it in items)
    harness = (HARNESS.replace("{ITEMS}", "{" + rows + "}").replace("SCRIPT", repr(str(script)))
               .replace("KNOWN_COMP", "101"))
    runtime, printed = lua54()
    runtime.execute(harness)
    lines = [l.split() for l in printed]
    expected = []
    for c in cmds:
        # component 101 was heard on channel 2; any other camera is sent on every channel 0..7
        chans = [2] if c.component == 101 else list(range(8))
        expected += [(ch, c) for ch in chans]
    assert len(lines) == len(expected)
    for fields, (ch, c) in zip(lines, expected):
        chan, msgid, tsys, tcomp, command = map(int, fields[:5])
        assert (chan, msgid, tsys, tcomp) == (ch, mavlink.MAVLINK_MSG_ID_COMMAND_LONG, 7, c.component)
        assert command == getattr(mavlink, c.command)
        got = [None if v == "nan" else float(v) for v in fields[5:]]
        assert same(got, c.params)
