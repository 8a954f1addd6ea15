-- armgate.lua: Wireshark dissectors for armgate.
--
--  * "armgate": the 31-byte client protocol on UDP (docs/protocol.md): command and its meaning,
--    the seven floats by what they mean for that command, the index (via slot, joint bank bit),
--    ER/WN texts with their codes, the status reply (SQ -> QS), and the signature block of a
--    signed datagram (docs/protocol.md, "Signed datagrams": link id, timestamp, tag; the tag
--    is shown, not verified: the dissector has no key).
--  * "armgate_can": the drives' CAN traffic (docs/drives.md): Elmo SimplIQ binary interpreter
--    commands (RPDO2, 0x300 + node) and replies (TPDO2, 0x280 + node) with PT writes called out,
--    NMT, SYNC, EMCY with the meanings the drive manager gives them (ER3x), heartbeats, expedited
--    SDO (the PDO mapping objects named); the PDO schedule's PT point (RPDO3, 0x400 + node) and
--    feedback (TPDO3, 0x380 + node: position, PT head and tail pointers), and the Time Stamp
--    (0x100: the controller's µs at the last SYNC); other PDOs are shown as raw bytes.
--
-- Install: copy this file into Wireshark's personal Lua plugins folder (Help > About Wireshark >
-- Folders > Personal Lua Plugins; on Linux ~/.local/lib/wireshark/plugins/), or run
--   tshark -X lua_script:tools/wireshark/armgate.lua -r capture.pcapng
-- The UDP port is a preference (Edit > Preferences > Protocols > ARMGATE), 7031 by default.
-- armgate-sim --pcap FILE writes captures with both.

---------------------------------------------------------------------------------------------
-- The client protocol
---------------------------------------------------------------------------------------------

local armgate = Proto("armgate", "armgate arm controller protocol")

local BANK2 = 0x80

-- Request characters -> what they do. Replies carry the characters reversed.
local commands = {
    BG = "Cartesian move to the stored goal",
    CM = "Change mode",
    GL = "Cartesian goal (position, quaternion)",
    GT = "Cartesian goal (position, RPY, duration)",
    jB = "Joint move to the stored goal",
    jC = "Clear joint via points",
    jE = "Run joint via points",
    jG = "Joint goal",
    jP = "Joint positions",
    jR = "Stop joint motion",
    jT = "Joint via point blend tolerance",
    jV = "Joint via point",
    jW = "Joint rates (stream)",
    ON = "Drives on",
    OF = "Drives off",
    PS = "Tool pose",
    RC = "Recalibrate",
    ST = "Stop",
    TM = "Temperatures",
    TW = "Tool twist (stream)",
    VC = "Clear Cartesian via points",
    VE = "Run Cartesian via points",
    VP = "Cartesian via point",
    VT = "Cartesian via point blend tolerance",
    SQ = "Status",
}

-- Codes of ER/WN texts (docs/protocol.md, docs/drives.md).
local text_codes = {
    [0] = "command not understood",
    [1] = "message undersized",
    [10] = "arm did not stop",
    [11] = "arm did not start",
    [12] = "joint limit (set-point clamped)",
    [13] = "stream held (workspace edge, or before a link's contact)",
    [20] = "command rejected",
    [21] = "workspace limit",
    [22] = "inverse kinematics divergence",
    [23] = "bad number",
    [24] = "bad index",
    [25] = "outside workspace",
    [26] = "beyond joint limit",
    [27] = "via point missed",
    [30] = "drive not answering",
    [31] = "drive error code",
    [32] = "drive emergency",
    [33] = "PT buffer underflow",
    [34] = "PT buffer overrun",
    [35] = "CAN bus off / send queue full",
    [36] = "drive lost the controller heartbeat",
    [37] = "wrong unit mode",
    [38] = "drive did not begin",
    [39] = "SDO abort",
}

local modes = { [0] = "off", [1] = "joint", [2] = "Cartesian" }
local drive_states = { [0] = "off", [1] = "starting", [2] = "running", [3] = "stopping", [4] = "faulted" }
local motions = {
    [0] = "idle", [1] = "joint move", [2] = "Cartesian move",
    [3] = "joint sequence", [4] = "Cartesian sequence", [5] = "velocity stream",
}

local f = {
    command = ProtoField.string("armgate.command", "Command"),
    meaning = ProtoField.string("armgate.meaning", "Meaning"),
    direction = ProtoField.string("armgate.direction", "Direction"),
    value = ProtoField.float("armgate.value", "Value (unused)"),
    x = ProtoField.float("armgate.x", "x (m)"),
    y = ProtoField.float("armgate.y", "y (m)"),
    z = ProtoField.float("armgate.z", "z (m)"),
    qx = ProtoField.float("armgate.qx", "Quaternion x"),
    qy = ProtoField.float("armgate.qy", "Quaternion y"),
    qz = ProtoField.float("armgate.qz", "Quaternion z"),
    qw = ProtoField.float("armgate.qw", "Quaternion w"),
    roll = ProtoField.float("armgate.roll", "Roll (rad)"),
    pitch = ProtoField.float("armgate.pitch", "Pitch (rad)"),
    yaw = ProtoField.float("armgate.yaw", "Yaw (rad)"),
    time = ProtoField.float("armgate.time", "Duration (s)"),
    blend = ProtoField.float("armgate.blend", "Blend tolerance (VT: m + rad, jT: rad; < 0: default)"),
    vx = ProtoField.float("armgate.vx", "vx (m/s)"),
    vy = ProtoField.float("armgate.vy", "vy (m/s)"),
    vz = ProtoField.float("armgate.vz", "vz (m/s)"),
    wx = ProtoField.float("armgate.wx", "wx (rad/s)"),
    wy = ProtoField.float("armgate.wy", "wy (rad/s)"),
    wz = ProtoField.float("armgate.wz", "wz (rad/s)"),
    hold = ProtoField.float("armgate.hold", "Holds for (s)"),
    tool_frame = ProtoField.bool("armgate.tool_frame", "Tool frame", 8, nil, 0x01),
    mode = ProtoField.float("armgate.mode", "Mode"),
    joint = ProtoField.float("armgate.joint", "Joint"),
    temperature = ProtoField.float("armgate.temperature", "Temperature (degC)"),
    index = ProtoField.uint8("armgate.index", "Index", base.HEX),
    slot = ProtoField.uint8("armgate.slot", "Via slot", base.DEC, nil, 0x7F),
    bank2 = ProtoField.bool("armgate.bank2", "Joint bank 2 (joints 7..)", 8, nil, BANK2),
    text = ProtoField.string("armgate.text", "Text"),
    severity = ProtoField.string("armgate.severity", "Severity"),
    code = ProtoField.uint8("armgate.code", "Code", base.DEC, text_codes),
    reason = ProtoField.string("armgate.reason", "Reason"),
    status_mode = ProtoField.float("armgate.status.mode", "Mode"),
    status_drives = ProtoField.float("armgate.status.drives", "Drive state"),
    status_fault = ProtoField.float("armgate.status.fault", "Drive fault (ER3x code, 0 none)"),
    status_joints = ProtoField.float("armgate.status.joints", "Joint count"),
    status_motion = ProtoField.float("armgate.status.motion", "Motion"),
    status_refusals = ProtoField.float("armgate.status.refusals", "Refusals since start"),
    status_uptime = ProtoField.float("armgate.status.uptime", "Seconds since start"),
    status_name = ProtoField.string("armgate.status.name", "Robot name"),
    nearest_gap = ProtoField.float("armgate.nearest.gap", "Nearest gap (m)"),
    nearest_link = ProtoField.float("armgate.nearest.link", "Link (-1: nothing measured)"),
    nearest_kind = ProtoField.float("armgate.nearest.kind", "Obstacle kind"),
    nearest_number = ProtoField.float("armgate.nearest.number", "Obstacle number"),
    nearest_margin = ProtoField.float("armgate.nearest.margin", "Margin (m)"),
    signing_policy = ProtoField.float("armgate.signing.policy", "Signing policy"),
    signing_signed = ProtoField.float("armgate.signing.signed", "Signed datagrams served"),
    signing_unsigned = ProtoField.float("armgate.signing.unsigned", "Unsigned datagrams served"),
    signing_dropped_unsigned = ProtoField.float("armgate.signing.dropped_unsigned", "Dropped: unsigned"),
    signing_dropped_truncated = ProtoField.float("armgate.signing.dropped_truncated", "Dropped: block truncated"),
    signing_dropped_forged = ProtoField.float("armgate.signing.dropped_forged", "Dropped: forged (wrong tag)"),
    signing_dropped_replayed = ProtoField.float("armgate.signing.dropped_replayed", "Dropped: replayed (old timestamp)"),
    signature = ProtoField.bytes("armgate.signature", "Signature block"),
    signature_link = ProtoField.uint8("armgate.signature.link", "Link id", base.DEC,
        { [0] = "controller" }),
    signature_timestamp = ProtoField.uint64("armgate.signature.timestamp",
        "Timestamp (10 us since 2015-01-01 UTC)"),
    signature_time = ProtoField.string("armgate.signature.time", "Time (UTC)"),
    signature_tag = ProtoField.bytes("armgate.signature.tag", "Tag (HMAC-SHA256, 48 bits; not verified)"),
}
armgate.fields = f

armgate.prefs.port = Pref.uint("UDP port", 7031, "The controller's UDP port")

local XYZ = { f.x, f.y, f.z }
local XYZ_QUAT = { f.x, f.y, f.z, f.qx, f.qy, f.qz, f.qw }
local XYZ_RPY_T = { f.x, f.y, f.z, f.roll, f.pitch, f.yaw, f.time }
local TWIST = { f.vx, f.vy, f.vz, f.wx, f.wy, f.wz }
local TWIST_HOLD = { f.vx, f.vy, f.vz, f.wx, f.wy, f.wz, f.hold }

-- What f0..f6 mean: by request characters, for the request ("req") and its reply ("rep").
-- "joints" = joint values, numbered from 1 or (bank 2) from 7; "temps" the same for TM.
local layouts = {
    CM = { req = { f.mode }, rep = { f.mode } },
    GL = { req = XYZ_QUAT, rep = XYZ_QUAT },
    GT = { req = XYZ_RPY_T, rep = XYZ_RPY_T },
    VP = { req = XYZ_RPY_T, rep = XYZ_RPY_T },
    PS = { rep = XYZ_QUAT },
    jG = { req = "joints6", rep = "joints6" },
    RC = { req = "joints6" },
    jV = { req = "joints6t", rep = "joints6t" },
    VT = { req = { f.blend }, rep = { f.blend } },
    jT = { req = { f.blend }, rep = { f.blend } },
    TW = { req = TWIST, rep = TWIST_HOLD },
    jW = { req = "rates6", rep = "rates6h" },
    jP = { rep = "joints7" },
    TM = { rep = "temps7" },
}

local function add_joints(tree, tvb, count, first, field, unit, with_time)
    for k = 0, count - 1 do
        local range = tvb(2 + 4 * k, 4)
        local v = range:le_float()
        local label = string.format("Joint %d: %.6g %s", first + k, v, unit)
        if field == f.temperature and v == -100 then
            label = label .. " (no reading yet)"
        elseif field == f.temperature and v == -1000 then
            label = label .. " (no such joint)"
        end
        tree:add_le(field, range, v):set_text(label)
    end
    if with_time then
        tree:add_le(f.time, tvb(26, 4))
    end
end

local function add_values(tree, tvb, layout, index)
    local first = (bit.band(index, BANK2) ~= 0) and 7 or 1
    local used = 0
    if layout == "joints6" or layout == "joints6t" then
        add_joints(tree, tvb, 6, first, f.joint, "rad", layout == "joints6t")
        used = layout == "joints6t" and 7 or 6
    elseif layout == "rates6" or layout == "rates6h" then
        add_joints(tree, tvb, 6, first, f.joint, "rad/s", false)
        used = 6
        if layout == "rates6h" then
            tree:add_le(f.hold, tvb(26, 4))
            used = 7
        end
    elseif layout == "joints7" then
        add_joints(tree, tvb, 7, first, f.joint, "rad", false)
        used = 7
    elseif layout == "temps7" then
        add_joints(tree, tvb, 7, first, f.temperature, "degC", false)
        used = 7
    elseif type(layout) == "table" then
        for k, field in ipairs(layout) do
            tree:add_le(field, tvb(2 + 4 * (k - 1), 4))
        end
        used = #layout
    end
    for k = used, 6 do
        local range = tvb(2 + 4 * k, 4)
        if range:le_float() ~= 0 then
            tree:add_le(f.value, range):prepend_text(string.format("f%d ", k))
        end
    end
end

local function summary(tvb, layout)
    if layout == XYZ_QUAT or layout == XYZ_RPY_T then
        return string.format(" x=%.4f y=%.4f z=%.4f", tvb(2, 4):le_float(), tvb(6, 4):le_float(),
            tvb(10, 4):le_float())
    elseif layout == TWIST or layout == TWIST_HOLD then
        return string.format(" v=(%.4g, %.4g, %.4g) w=(%.4g, %.4g, %.4g)", tvb(2, 4):le_float(),
            tvb(6, 4):le_float(), tvb(10, 4):le_float(), tvb(14, 4):le_float(),
            tvb(18, 4):le_float(), tvb(22, 4):le_float())
    elseif layout ~= nil and type(layout) == "table" then
        return string.format(" %.4g", tvb(2, 4):le_float())
    elseif layout ~= nil then
        return string.format(" %.4f ...", tvb(2, 4):le_float())
    end
    return ""
end

local signing_policies = {
    [0] = "off (no key)", [1] = "signed only", [2] = "unsigned may read", [3] = "unsigned allowed",
}

-- QS index 4: the signing counters.
local function dissect_signing(tree, tvb)
    local fields = {
        f.signing_policy, f.signing_signed, f.signing_unsigned, f.signing_dropped_unsigned,
        f.signing_dropped_truncated, f.signing_dropped_forged, f.signing_dropped_replayed,
    }
    local v = {}
    for k, field in ipairs(fields) do
        local range = tvb(2 + 4 * (k - 1), 4)
        v[k] = range:le_float()
        local item = tree:add_le(field, range)
        if k == 1 and signing_policies[math.floor(v[k] + 0.5)] then
            item:append_text(" (" .. signing_policies[math.floor(v[k] + 0.5)] .. ")")
        end
    end
    return string.format(" signing=%s dropped=%d", signing_policies[math.floor(v[1] + 0.5)] or v[1],
        v[4] + v[5] + v[6] + v[7])
end

-- The signature block after the 31-byte message (bytes 31..43), if there is one.
local function dissect_signature(tree, tvb)
    local len = tvb:len()
    if len <= 31 then return "" end
    if len < 44 then
        tree:add_expert_info(PI_MALFORMED, PI_ERROR,
            "signature block truncated (the controller drops it)")
        return " [signature truncated]"
    end
    local block = tree:add(f.signature, tvb(31, 13))
    local link = tvb(31, 1):uint()
    block:add(f.signature_link, tvb(31, 1))
    local timestamp = tvb(32, 6):le_uint64()
    block:add_le(f.signature_timestamp, tvb(32, 6))
    local seconds = math.floor(timestamp:tonumber() / 100000) + 1420070400
    block:add(f.signature_time, tvb(32, 6), os.date("!%Y-%m-%d %H:%M:%S", seconds))
    block:add(f.signature_tag, tvb(38, 6))
    return string.format(" [signed link=%d t=%s]", link, tostring(timestamp))
end

-- QS index 7: the body's nearest gap and its pair; the kinds as protocol/grammar.json's
-- "obstacles" (name, short form of the texts).
local obstacle_kinds = { [0] = { "box", "B" }, [1] = { "link", "L" }, [2] = { "bounds", "out" } }

local function dissect_nearest(tree, tvb)
    local fields = { f.nearest_gap, f.nearest_link, f.nearest_kind, f.nearest_number, f.nearest_margin }
    local v = {}
    for k, field in ipairs(fields) do
        local range = tvb(2 + 4 * (k - 1), 4)
        v[k] = range:le_float()
        local item = tree:add_le(field, range)
        local kind = obstacle_kinds[math.floor(v[k] + 0.5)]
        if k == 3 and kind then item:append_text(" (" .. kind[1] .. ")") end
    end
    if v[2] < 0 then return " nearest=none" end
    local kind = obstacle_kinds[math.floor(v[3] + 0.5)] or { "?", "?" }
    local what = kind[2] == "out" and "out" or string.format("%s%d", kind[2], math.floor(v[4] + 0.5))
    return string.format(" nearest=%.1f mm L%d %s", v[1] * 1000, math.floor(v[2] + 0.5), what)
end

local function dissect_status(tree, tvb, index)
    if index == 4 then
        return dissect_signing(tree, tvb)
    end
    if index == 7 then
        return dissect_nearest(tree, tvb)
    end
    if index == 1 then
        local name = tvb(2, 28):stringz()
        tree:add(f.status_name, tvb(2, 28), name)
        return " name=" .. name
    end
    local function add(field, k, names)
        local range = tvb(2 + 4 * k, 4)
        local v = range:le_float()
        local item = tree:add_le(field, range)
        local label = names and names[math.floor(v + 0.5)]
        if label then item:append_text(" (" .. label .. ")") end
        return v
    end
    local mode = add(f.status_mode, 0, modes)
    local drives = add(f.status_drives, 1, drive_states)
    local fault = math.floor(add(f.status_fault, 2) + 0.5)
    add(f.status_joints, 3)
    local motion = add(f.status_motion, 4, motions)
    add(f.status_refusals, 5)
    add(f.status_uptime, 6)
    local info = string.format(" mode=%s drives=%s motion=%s", modes[math.floor(mode + 0.5)] or mode,
        drive_states[math.floor(drives + 0.5)] or drives, motions[math.floor(motion + 0.5)] or motion)
    if fault ~= 0 then info = info .. string.format(" fault=ER%02d", fault) end
    return info
end

function armgate.dissector(tvb, pinfo, root)
    if tvb:len() < 2 then return 0 end
    pinfo.cols.protocol = "armgate"
    local tree = root:add(armgate, tvb(0, math.min(tvb:len(), 31)))
    local chars = tvb(0, 2):string()
    if chars == "ER" or chars == "WN" then
        local text = tvb(0, math.min(tvb:len(), 30)):stringz()
        tree:add(f.text, tvb(0, #text), text)
        tree:add(f.severity, tvb(0, 2), chars == "ER" and "error" or "warning")
        local code = tonumber(text:sub(3, 4))
        if code then tree:add(f.code, tvb(2, 2), code) end
        if #text > 5 then tree:add(f.reason, tvb(5, #text - 5), text:sub(6)) end
        pinfo.cols.info = text .. dissect_signature(tree, tvb)
        return tvb:len()
    end
    if tvb:len() < 31 then
        tree:add_expert_info(PI_MALFORMED, PI_ERROR, "shorter than 31 bytes (the controller answers ER01)")
        pinfo.cols.info = chars .. " (undersized)"
        return tvb:len()
    end
    local index = tvb(30, 1):uint()
    local request = commands[chars] ~= nil
    local base_chars = request and chars or chars:reverse()
    local meaning = commands[base_chars]
    tree:add(f.command, tvb(0, 2), chars)
    tree:add(f.direction, tvb(0, 2), request and "request" or (meaning and "reply" or "unknown"))
    if meaning then tree:add(f.meaning, tvb(0, 2), meaning) end
    local info = chars .. " " .. (request and "request" or "reply")
    if meaning then info = info .. " (" .. meaning .. ")" end
    if base_chars == "SQ" then
        if not request then info = info .. dissect_status(tree, tvb, index) end
    else
        local layout = layouts[base_chars]
        if layout then
            if request then layout = layout.req else layout = layout.rep end
        end
        add_values(tree, tvb, layout, index)
        info = info .. summary(tvb, layout)
    end
    local index_item = tree:add(f.index, tvb(30, 1))
    if base_chars == "jV" or base_chars == "VP" or base_chars == "jT" or base_chars == "VT" then
        index_item:add(f.slot, tvb(30, 1))
        info = info .. string.format(" slot=%d", bit.band(index, 0x7F))
    end
    if base_chars == "TW" then
        index_item:add(f.tool_frame, tvb(30, 1))
        if bit.band(index, 0x01) ~= 0 then info = info .. " [tool frame]" end
    else
        index_item:add(f.bank2, tvb(30, 1))
    end
    if bit.band(index, BANK2) ~= 0 then info = info .. " [bank 2]" end
    pinfo.cols.info = info .. dissect_signature(tree, tvb)
    return tvb:len()
end

local udp_port = armgate.prefs.port
DissectorTable.get("udp.port"):add(udp_port, armgate)

function armgate.prefs_changed()
    if armgate.prefs.port ~= udp_port then
        DissectorTable.get("udp.port"):remove(udp_port, armgate)
        udp_port = armgate.prefs.port
        DissectorTable.get("udp.port"):add(udp_port, armgate)
    end
end

---------------------------------------------------------------------------------------------
-- The drives' CAN traffic
---------------------------------------------------------------------------------------------

local can = Proto("armgate_can", "armgate CAN (CANopen / Elmo SimplIQ)")

local mnemonics = {
    BG = "begin motion", ST = "stop motion", MO = "motor on/off", UM = "unit mode",
    PX = "main position", VX = "velocity", PT = "PT motion / read index",
    MP = "motion parameter", QP = "PT position table", QT = "PT time table",
    TI = "temperature", TC = "torque command", IQ = "active current", JV = "jog velocity",
    PA = "absolute position", EC = "error code",
}
local motion_parameters = {
    [1] = "first table index", [2] = "last table index", [3] = "cyclic",
    [4] = "segment time (samples)", [5] = "queue-low threshold", [6] = "write pointer",
}
local nmt_commands = {
    [0x01] = "start", [0x02] = "stop", [0x80] = "enter pre-operational",
    [0x81] = "reset node", [0x82] = "reset communication",
}
local nmt_states = { [0x00] = "boot-up", [0x04] = "stopped", [0x05] = "operational", [0x7F] = "pre-operational" }
local sdo_aborts = {
    [0x05040000] = "SDO protocol timed out",
    [0x05040001] = "command specifier not valid",
    [0x06010000] = "unsupported access",
    [0x06010001] = "attempt to read a write-only object",
    [0x06010002] = "attempt to write a read-only object",
    [0x06020000] = "object does not exist",
    [0x06040041] = "object cannot be mapped",
    [0x06040042] = "mapping exceeds the PDO length",
    [0x06070010] = "data type does not match",
    [0x06090011] = "sub-index does not exist",
    [0x06090030] = "value range exceeded",
    [0x08000000] = "general error",
    [0x08000022] = "not in the present device state (PDO valid, or mapping not cleared)",
}
local sdo_objects = {
    [0x1016] = "consumer heartbeat", [0x1017] = "producer heartbeat",
    [0x1402] = "RPDO3 communication", [0x1602] = "RPDO3 mapping",
    [0x1802] = "TPDO3 communication", [0x1A02] = "TPDO3 mapping",
    [0x2040] = "group id (synchronized commands)",
}
local elmo_codes = {
    [0x34] = "PT queue full: an unexecuted point was overwritten (ER34)",
    [0x08] = "PT motion terminated (ER33 if the reason is underflow)",
    [0x09] = "CAN message lost (ER32)",
    [0x56] = "PT queue low (warning)",
    [0x5B] = "PT write pointer out of range (ER32)",
    [0x5C] = "PDO not mapped (ER32)",
}
local terminate_reasons = { [1] = "end of a non-cyclic table", [2] = "bad segment time", [3] = "read pointer reached write pointer (underflow)" }

local c = {
    node = ProtoField.uint8("armgate_can.node", "Node"),
    service = ProtoField.string("armgate_can.service", "Service"),
    mnemonic = ProtoField.string("armgate_can.mnemonic", "Interpreter command"),
    meaning = ProtoField.string("armgate_can.meaning", "Meaning"),
    array_index = ProtoField.uint16("armgate_can.index", "Array index"),
    kind = ProtoField.string("armgate_can.kind", "Kind"),
    int = ProtoField.int32("armgate_can.int", "Value (integer)"),
    float = ProtoField.float("armgate_can.float", "Value (float)"),
    error_code = ProtoField.uint8("armgate_can.error_code", "Elmo error code (EC)"),
    pt_slot = ProtoField.uint16("armgate_can.pt.slot", "PT write: table slot"),
    pt_counts = ProtoField.int32("armgate_can.pt.counts", "PT write: position (counts)"),
    fb_position = ProtoField.int32("armgate_can.feedback.position", "Position PX (counts)"),
    fb_head = ProtoField.uint16("armgate_can.feedback.head", "PT head (write) pointer"),
    fb_tail = ProtoField.uint16("armgate_can.feedback.tail", "PT tail (read) pointer"),
    nmt_command = ProtoField.uint8("armgate_can.nmt.command", "NMT command", base.HEX, nmt_commands),
    nmt_target = ProtoField.uint8("armgate_can.nmt.node", "NMT node (0 = all)"),
    hb_state = ProtoField.uint8("armgate_can.heartbeat.state", "Heartbeat state", base.HEX, nmt_states, 0x7F),
    sync_counter = ProtoField.uint8("armgate_can.sync.counter", "SYNC counter"),
    time_stamp = ProtoField.uint32("armgate_can.time_stamp.micros", "Controller clock at the last SYNC (µs)"),
    emcy_code = ProtoField.uint16("armgate_can.emcy.code", "EMCY error code", base.HEX),
    emcy_register = ProtoField.uint8("armgate_can.emcy.register", "Error register", base.HEX),
    emcy_meaning = ProtoField.string("armgate_can.emcy.meaning", "EMCY meaning"),
    emcy_elmo = ProtoField.uint8("armgate_can.emcy.elmo", "Elmo code", base.HEX),
    emcy_field1 = ProtoField.uint16("armgate_can.emcy.field1", "Elmo field 1"),
    emcy_field2 = ProtoField.uint16("armgate_can.emcy.field2", "Elmo field 2"),
    sdo_cs = ProtoField.uint8("armgate_can.sdo.cs", "SDO command specifier", base.HEX),
    sdo_object = ProtoField.uint16("armgate_can.sdo.object", "SDO object", base.HEX),
    sdo_subindex = ProtoField.uint8("armgate_can.sdo.subindex", "SDO sub-index"),
    sdo_data = ProtoField.uint32("armgate_can.sdo.data", "SDO data", base.HEX),
    sdo_abort = ProtoField.uint32("armgate_can.sdo.abort", "SDO abort code", base.HEX, sdo_aborts),
    data = ProtoField.bytes("armgate_can.data", "Data"),
}
can.fields = c

local can_id_field = Field.new("can.id")

-- Interpreter frame: 2 letters, index (14 bits, byte 3 bits 0-5), flags (bit 7 float, bit 6
-- error), value.
local function dissect_interpreter(tvb, tree, node, is_command)
    if tvb:len() < 4 then return "interpreter frame, too short" end
    local m = tvb(0, 2):string()
    local high = tvb(3, 1):uint()
    local index = tvb(2, 1):uint() + bit.band(high, 0x3F) * 256
    local is_float = bit.band(high, 0x80) ~= 0
    local is_error = bit.band(high, 0x40) ~= 0
    tree:add(c.mnemonic, tvb(0, 2), m)
    if mnemonics[m] then tree:add(c.meaning, tvb(0, 2), mnemonics[m]) end
    tree:add(c.array_index, tvb(2, 2), index)
    local name = index ~= 0 and string.format("%s[%d]", m, index) or m
    if m == "MP" and motion_parameters[index] then
        tree:add(c.meaning, tvb(2, 1), motion_parameters[index])
    end
    if not is_command and is_error then
        local code = tvb:len() >= 5 and tvb(4, 1):uint() or 0
        tree:add(c.kind, tvb(3, 1), "error reply")
        tree:add(c.error_code, tvb(4, 1), code)
        return string.format("node %d: %s refused, error code %d", node, name, code)
    end
    if tvb:len() < 8 then
        tree:add(c.kind, tvb(0, 4), is_command and "query / execute" or "reply")
        return string.format("node %d: %s %s", node, name, is_command and "?" or "reply")
    end
    local value_text
    if is_float then
        local v = tvb(4, 4):le_float()
        tree:add_le(c.float, tvb(4, 4))
        value_text = string.format("%.6g", v)
    else
        local v = tvb(4, 4):le_int()
        tree:add_le(c.int, tvb(4, 4))
        value_text = tostring(v)
    end
    if is_command then
        if m == "QP" then
            tree:add(c.kind, tvb(0, 4), "PT write")
            tree:add(c.pt_slot, tvb(2, 2), index)
            tree:add_le(c.pt_counts, tvb(4, 4))
            return string.format("node %d: PT write QP[%d] = %s", node, index, value_text)
        end
        tree:add(c.kind, tvb(0, 4), "set")
        return string.format("node %d: %s = %s", node, name, value_text)
    end
    tree:add(c.kind, tvb(0, 4), "reply")
    return string.format("node %d: %s is %s", node, name, value_text)
end

local function dissect_emcy(tvb, tree, node)
    local function byte(k) return tvb:len() > k and tvb(k, 1):uint() or 0 end
    local code = tvb:len() >= 2 and tvb(0, 2):le_uint() or 0
    local register = byte(2)
    if tvb:len() >= 2 then tree:add_le(c.emcy_code, tvb(0, 2)) end
    if tvb:len() >= 3 then tree:add(c.emcy_register, tvb(2, 1)) end
    local meaning
    if code == 0 then
        meaning = "error reset"
    elseif code == 0x8380 and register == 0x81 then
        meaning = "digital Hall sensor (ignored, as the seed did)"
    elseif code == 0x8130 then
        meaning = "lost the controller heartbeat (ER36)"
    elseif code == 0xFF00 then
        local elmo = byte(3)
        tree:add(c.emcy_elmo, tvb(3, 1))
        local f1 = tvb:len() >= 6 and tvb(4, 2):le_uint() or 0
        local f2 = tvb:len() >= 8 and tvb(6, 2):le_uint() or 0
        if tvb:len() >= 6 then tree:add_le(c.emcy_field1, tvb(4, 2)) end
        if tvb:len() >= 8 then tree:add_le(c.emcy_field2, tvb(6, 2)) end
        meaning = elmo_codes[elmo] or string.format("Elmo code 0x%02X (ER32)", elmo)
        if elmo == 0x08 then
            meaning = string.format("PT motion terminated: %s, write pointer %d%s",
                terminate_reasons[f2] or ("reason " .. f2), f1, f2 == 3 and " (ER33)" or " (ER32)")
        elseif elmo == 0x56 then
            meaning = string.format("PT queue low: write pointer %d, read pointer %d (warning)", f1, f2)
        elseif elmo == 0x34 then
            meaning = string.format("PT queue full at index %d: an unexecuted point was overwritten (ER34)", f1)
        end
    else
        meaning = string.format("emergency 0x%04X (ER32)", code)
    end
    tree:add(c.emcy_meaning, tvb(0, math.min(tvb:len(), 8)), meaning)
    return string.format("node %d: EMCY %04X: %s", node, code, meaning)
end

local function dissect_sdo(tvb, tree, node, is_request)
    if tvb:len() < 8 then return "SDO, too short" end
    local cs = tvb(0, 1):uint()
    local object = tvb(1, 2):le_uint()
    local sub = tvb(3, 1):uint()
    tree:add(c.sdo_cs, tvb(0, 1))
    tree:add_le(c.sdo_object, tvb(1, 2))
    tree:add(c.sdo_subindex, tvb(3, 1))
    local where = string.format("%04X:%d", object, sub)
    if sdo_objects[object] then
        tree:add(c.meaning, tvb(1, 3), sdo_objects[object])
        where = where .. " (" .. sdo_objects[object] .. ")"
    end
    local data = tvb(4, 4):le_uint()
    local kind
    if cs == 0x80 then
        tree:add_le(c.sdo_abort, tvb(4, 4))
        return string.format("node %d: SDO abort %s: %08X %s", node, where, data, sdo_aborts[data] or "")
    elseif is_request and bit.band(cs, 0xE3) == 0x23 then
        tree:add_le(c.sdo_data, tvb(4, 4))
        kind = string.format("download %s = 0x%08X", where, data)
        if object == 0x1016 then
            kind = kind .. string.format(" (consumer heartbeat: node %d, %d ms)",
                bit.band(bit.rshift(data, 16), 0x7F), bit.band(data, 0xFFFF))
        end
    elseif is_request and cs == 0x40 then
        kind = "upload " .. where .. "?"
    elseif not is_request and cs == 0x60 then
        kind = "download " .. where .. " done"
    elseif not is_request and bit.band(cs, 0xE3) == 0x43 then
        tree:add_le(c.sdo_data, tvb(4, 4))
        kind = string.format("upload %s is 0x%08X", where, data)
    else
        kind = string.format("command specifier 0x%02X %s", cs, where)
    end
    return string.format("node %d: SDO %s", node, kind)
end

local function service_of(id)
    local fn, node = bit.band(id, 0x780), bit.band(id, 0x7F)
    if id == 0x000 then return "NMT", 0 end
    if id == 0x080 then return "SYNC", 0 end
    if id == 0x100 then return "Time Stamp", 0 end
    if node == 0 then return nil, 0 end
    local services = {
        [0x080] = "EMCY", [0x180] = "TPDO1", [0x200] = "RPDO1", [0x280] = "TPDO2 (interpreter reply)",
        [0x300] = "RPDO2 (interpreter command)", [0x380] = "TPDO3 (PT feedback)", [0x400] = "RPDO3 (PT point)",
        [0x480] = "TPDO4", [0x500] = "RPDO4", [0x580] = "SDO response", [0x600] = "SDO request",
        [0x700] = "Heartbeat",
    }
    return services[fn], node
end

function can.dissector(tvb, pinfo, root)
    local id_value = can_id_field()
    if id_value == nil then return 0 end
    local id = id_value.value
    local service, node = service_of(id)
    if service == nil then return 0 end
    pinfo.cols.protocol = "armgate CAN"
    local tree = root:add(can, tvb())
    tree:add(c.service, service)
    if node ~= 0 then tree:add(c.node, node) end
    local fn = bit.band(id, 0x780)
    local info
    if service == "NMT" then
        if tvb:len() >= 2 then
            tree:add(c.nmt_command, tvb(0, 1))
            tree:add(c.nmt_target, tvb(1, 1))
            local target = tvb(1, 1):uint()
            info = string.format("NMT %s, %s", nmt_commands[tvb(0, 1):uint()] or "?",
                target == 0 and "all nodes" or ("node " .. target))
        else
            info = "NMT, too short"
        end
    elseif service == "SYNC" then
        if tvb:len() >= 1 then tree:add(c.sync_counter, tvb(0, 1)) end
        info = "SYNC"
    elseif service == "Time Stamp" then
        if tvb:len() == 4 then
            tree:add_le(c.time_stamp, tvb(0, 4))
            info = string.format("Time Stamp %d µs (the last SYNC)", tvb(0, 4):le_uint())
        else
            info = "Time Stamp, not 4 bytes"
        end
    elseif fn == 0x080 then
        info = dissect_emcy(tvb, tree, node)
    elseif fn == 0x300 then
        info = dissect_interpreter(tvb, tree, node, true)
    elseif fn == 0x280 then
        info = dissect_interpreter(tvb, tree, node, false)
    elseif fn == 0x400 and tvb:len() == 4 then
        tree:add(c.kind, tvb(), "PT point at the write pointer")
        tree:add_le(c.pt_counts, tvb(0, 4))
        info = string.format("node %d: PT point %d", node, tvb(0, 4):le_int())
    elseif fn == 0x380 and tvb:len() == 8 then
        tree:add_le(c.fb_position, tvb(0, 4))
        tree:add_le(c.fb_head, tvb(4, 2))
        tree:add_le(c.fb_tail, tvb(6, 2))
        info = string.format("node %d: PX %d, PT head %d, tail %d", node, tvb(0, 4):le_int(),
            tvb(4, 2):le_uint(), tvb(6, 2):le_uint())
    elseif fn == 0x600 then
        info = dissect_sdo(tvb, tree, node, true)
    elseif fn == 0x580 then
        info = dissect_sdo(tvb, tree, node, false)
    elseif fn == 0x700 then
        if tvb:len() >= 1 then
            tree:add(c.hb_state, tvb(0, 1))
            local state = bit.band(tvb(0, 1):uint(), 0x7F)
            info = string.format("Heartbeat node %d%s: %s", node, node == 127 and " (controller)" or "",
                nmt_states[state] or string.format("state 0x%02X", state))
        else
            info = "Heartbeat, empty"
        end
    else
        if tvb:len() > 0 then tree:add(c.data, tvb()) end
        info = string.format("%s node %d", service, node)
    end
    pinfo.cols.info = info
    return tvb:len()
end

-- Every standard identifier: the CAN dissector tries "can.id" before its heuristics. A
-- Wireshark without that table gets a heuristic dissector instead.
local ok, can_ids = pcall(DissectorTable.get, "can.id")
if ok and can_ids then
    for id = 0, 0x7FF do
        can_ids:add(id, can)
    end
else
    can:register_heuristic("can", function(tvb, pinfo, root)
        return can.dissector(tvb, pinfo, root) > 0
    end)
end
