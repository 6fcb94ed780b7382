-- SPDX-License-Identifier: Apache-2.0
-- libmica for LuaJIT: the C API through the ffi, plus a few helpers.
--
--   local mica = require("mica")
--   local world = mica.world{ gravity = {0, 0, 0}, solver = mica.C.MICA_SOLVER_MICA }
--   local cube = world:create_box({-0.05, 0, -0.05}, {0.05, 0.1, 0.05}, {4, 4, 4}, 5, { youngs_modulus = 1e4 })
--   local tool = world:create_tool{ radius = 0.02, position = {0, 0.125, 0} }
--   world:step(0.01)
--   local force, torque, contacts = world:tool_force(tool)
--
-- The declarations come from mica_cdef.lua, generated from include/mica/*.h at build time
-- (bindings/luajit/gen_cdef.py): require finds it in <build>/bindings/luajit. The library is
-- $MICA_LIBRARY, else libmica.so.<major> two folders above this file (a build tree), else the
-- one installed with this module (mica_install.lua, written by cmake --install), else
-- libmica.so.0 on the system's search path.
--
-- mica.C is the library namespace: every function of mica.h and mica_device.h, and the
-- constants (mica.C.MICA_OK). Errors (status < 0) raise a mica.Error {status, message};
-- warnings (status > 0) are returned: world:step() returns converged, status.
local ffi = require("ffi")

local M = {}

ffi.cdef(require("mica_cdef"))

local function module_dir()
  local source = debug.getinfo(1, "S").source
  return source:sub(1, 1) == "@" and source:sub(2):match("^(.*)/[^/]*$") or "."
end

local function file_exists(path)
  local f = io.open(path, "rb")
  if f then f:close() end
  return f ~= nil
end

local function load_library()
  local env = os.getenv("MICA_LIBRARY")
  if env and env ~= "" then return ffi.load(env), env end
  -- A build tree: <build>/bindings/luajit/mica.lua beside <build>/libmica.so.<major>.
  for _, up in ipairs({ "/../..", "/..", "" }) do
    local path = module_dir() .. up .. "/libmica.so.0"
    if file_exists(path) then return ffi.load(path), path end
  end
  -- An installed module: cmake --install wrote where it put libmica (mica_install.lua).
  local ok, install = pcall(require, "mica_install")
  if ok and type(install) == "table" and install.libdir then
    local path = install.libdir .. "/libmica.so.0"
    if file_exists(path) then return ffi.load(path), path end
  end
  return ffi.load("libmica.so.0"), "libmica.so.0"
end

local C, path = load_library()
M.C = C
M.path = path

-- Errors ----------------------------------------------------------------------------------

local Error = {}
Error.__index = Error
Error.__tostring = function(e)
  return (e.message ~= "" and e.message .. " " or "") .. "(" .. e.name .. ")"
end
M.Error = Error

local function raise(status, message)
  error(setmetatable({ status = status, message = message, name = ffi.string(C.mica_status_string(status)) },
                     Error))
end

-- Raises a mica.Error for status < 0 (message from mica_world_last_error(world_ptr), which may
-- be nil); returns the status otherwise, so warnings (status > 0) reach the caller.
function M.check(status, world_ptr)
  if status < 0 then raise(status, ffi.string(C.mica_world_last_error(world_ptr))) end
  return status
end
local check = M.check

function M.version() return C.mica_version() end

-- Definitions -----------------------------------------------------------------------------

-- The element count of a fixed-size C array (a cdata such as a def's double[3] field), else nil.
local function array_length(a)
  if type(a) ~= "cdata" or not tostring(ffi.typeof(a)):find("%]>$") then return nil end
  -- Its size over the distance between two elements (an element may itself be an array).
  return ffi.sizeof(a) / tonumber(ffi.cast("const char*", a + 1) - ffi.cast("const char*", a))
end

-- Copies a Lua table of exactly n numbers (of n tables for an array of arrays) into the C array
-- `array`; any other length raises "<name>: expected n values". (LuaJIT's own table initialiser
-- would repeat a lone value or leave the rest zero, or unset in a double[?].)
local function copy_values(array, n, values, name)
  if type(values) ~= "table" or #values ~= n then
    error(string.format("%s: expected %d values, got %s", name, n,
                        type(values) == "table" and #values or "a " .. type(values)), 0)
  end
  for i = 1, n do
    local element, where = array[i - 1], name .. "[" .. (i - 1) .. "]"
    local inner = array_length(element)
    if inner then
      copy_values(element, inner, values[i], where)
    elseif type(values[i]) ~= "number" then
      error(where .. ": expected a number, got a " .. type(values[i]), 0)
    else
      array[i - 1] = values[i]
    end
  end
end

-- Copies a table of field values (Lua tables for arrays, of the array's length) over a def.
local function fill(def, fields)
  for k, v in pairs(fields or {}) do
    assert(k ~= "struct_size", "struct_size is set by the *_init function")
    local n = type(v) == "table" and array_length(def[k])
    if n then
      copy_values(def[k], n, v, tostring(ffi.typeof(def)):match("<(.-)>") .. "." .. k)
    else
      def[k] = v
    end
  end
  return def
end

-- Each def is filled by its *_init function with this side's ffi.sizeof.
function M.world_def(fields)
  local d = ffi.new("mica_world_def")
  check(C.mica_world_def_init(d, ffi.sizeof(d), C.MICA_VERSION_NUMBER), nil)
  return fill(d, fields)
end

local function def_maker(ctype, init)
  return function(fields)
    local d = ffi.new(ctype)
    check(C[init](d, ffi.sizeof(d)), nil)
    return fill(d, fields)
  end
end
M.body_def = def_maker("mica_body_def", "mica_body_def_init")
M.lpc_def = def_maker("mica_lpc_def", "mica_lpc_def_init")
M.tool_def = def_maker("mica_tool_def", "mica_tool_def_init")
M.device_def = def_maker("mica_device_def", "mica_device_def_init")

-- A C array (of `ctype`, default double) of the n (default 3) numbers of a Lua table; `name` says
-- what they are in the message raised when the table has another length.
local function vec(values, n, name, ctype)
  n = n or 3
  local out = ffi.new((ctype or "double") .. "[?]", math.max(n, 1))
  copy_values(out, n, values, name or "vec")
  return out
end
M.vec = vec
local IDENTITY = { 1, 0, 0, 0 } -- the quaternion (w, x, y, z) of no rotation

-- World -----------------------------------------------------------------------------------

local World = {}
M.World = World
-- A closed world has no `ptr`: reading it (every method does) raises a mica.Error
-- (MICA_ERR_WRONG_STATE, "the world is closed").
World.__index = function(_, key)
  if key == "ptr" then raise(C.MICA_ERR_WRONG_STATE, "the world is closed") end
  return World[key]
end

-- Creates a world from a table of mica_world_def fields (or a filled mica_world_def). The
-- world is destroyed by world:close() or, failing that, by the garbage collector (ffi.gc).
function M.world(fields)
  local def = ffi.istype("mica_world_def", fields) and fields or M.world_def(fields)
  local out = ffi.new("mica_world*[1]")
  check(C.mica_world_create(def, out), nil)
  return setmetatable({ ptr = ffi.gc(out[0], C.mica_world_destroy), callbacks = {} }, World)
end

-- Destroys the world now (ids and position views die with it), then frees the callbacks made
-- for its devices.
-- A replay's world (replay.world) belongs to the replay: close() leaves it to replay:close().
function World:close()
  if not self:closed() and self.replay == nil then
    C.mica_world_destroy(ffi.gc(self.ptr, nil))
    self.ptr = nil
    for _, cb in ipairs(self.callbacks) do cb:free() end
    self.callbacks = {}
  end
end

function World:closed() return rawget(self, "ptr") == nil end

function World:check(status) return check(status, self.ptr) end

function World:last_error() return ffi.string(C.mica_world_last_error(self.ptr)) end

-- One step of dt seconds: returns converged (false on MICA_WARN_NOT_CONVERGED) and the status.
function World:step(dt)
  local status = self:check(C.mica_step(self.ptr, dt))
  return status == C.MICA_OK, status
end

function World:create_box(lo, hi, cells, tets_per_cell, fields)
  local id = ffi.new("mica_body_id[1]")
  self:check(C.mica_body_create_box(self.ptr, M.body_def(fields), vec(lo, 3, "create_box lo"),
                                    vec(hi, 3, "create_box hi"), vec(cells, 3, "create_box cells", "int32_t"),
                                    tets_per_cell or 5, id))
  return id[0]
end

-- A body from a mesh file: Gmsh .msh (2.2 or 4.1 ASCII) or a TetGen .node/.ele pair.
function World:create_body_from_file(path, fields)
  local id = ffi.new("mica_body_id[1]")
  self:check(C.mica_body_create_from_file(self.ptr, M.body_def(fields), path, id))
  return id[0]
end

-- A body from Lua tables: nodes {x1, y1, z1, x2, ...} (m), tets {a1, b1, c1, d1, ...} (0-based).
function World:create_body(nodes, tets, fields)
  assert(#nodes % 3 == 0 and #tets % 4 == 0, "nodes: 3 values a node, tets: 4 indices a tet")
  local id = ffi.new("mica_body_id[1]")
  self:check(C.mica_body_create(self.ptr, M.body_def(fields), ffi.new("double[?]", #nodes, nodes), #nodes / 3,
                                ffi.new("int32_t[?]", #tets, tets), #tets / 4, id))
  return id[0]
end

function World:destroy_body(body) self:check(C.mica_body_destroy(self.ptr, body)) end

function World:create_tool(fields)
  local id = ffi.new("mica_tool_id[1]")
  self:check(C.mica_tool_create(self.ptr, M.tool_def(fields), id))
  return id[0]
end

-- Runs a buffer-protocol call (size query, then fill): returns an int32_t array and its count.
-- (`width` indices per item: 4 for tets; default 1.)
local function read_indices(self, call, width)
  local count = ffi.new("int32_t[1]")
  self:check(call(nil, 0, count))
  local out = ffi.new("int32_t[?]", math.max((width or 1) * count[0], 1))
  self:check(call(out, count[0], count))
  return out, count[0]
end

function World:select_nodes_by_plane(body, point, normal, tolerance, use_rest)
  local p, n = vec(point, 3, "select_nodes_by_plane point"), vec(normal, 3, "select_nodes_by_plane normal")
  return read_indices(self, function(out, cap, count)
    return C.mica_body_select_nodes_by_plane(self.ptr, body, p, n, tolerance or 1e-9,
                                             use_rest == false and 0 or 1, out, cap, count)
  end)
end

-- Runs a buffer-protocol call for doubles (size query, then fill): returns a double array of
-- `width` values per item and the item count.
local function read_doubles(self, call, width)
  local count = ffi.new("int32_t[1]")
  self:check(call(nil, 0, count))
  local out = ffi.new("double[?]", math.max(width * count[0], 1))
  self:check(call(out, count[0], count))
  return out, count[0]
end

-- Since 0.6: a body's tets (int32_t[4 * t], 0-based) and the region of each (int32_t[t]).
function World:tets(body)
  return read_indices(self, function(out, cap, count) return C.mica_body_get_tets(self.ptr, body, out, cap, count) end, 4)
end
function World:tet_regions(body)
  return read_indices(self, function(out, cap, count)
    return C.mica_body_get_tet_regions(self.ptr, body, out, cap, count)
  end)
end

-- Materials per tet: Lua tables (or nil to keep that property) of Young's modulus (Pa), Poisson
-- ratio and density (kg/m^3), one value per tet. Rebuilds the body's stiffness, mass, damping.
function World:set_materials(body, youngs_modulus, poisson_ratio, density)
  local counts = ffi.new("int32_t[2]")
  self:check(C.mica_body_get_counts(self.ptr, body, counts, counts + 1, nil))
  local tets = counts[1]
  local function array(values, name)
    if values == nil then return nil end
    assert(#values == tets, name .. ": one value per tet")
    return ffi.new("double[?]", tets, values)
  end
  self:check(C.mica_body_set_materials(self.ptr, body, array(youngs_modulus, "youngs_modulus"),
                                       array(poisson_ratio, "poisson_ratio"), array(density, "density"), tets))
end

-- Resection: removes the tets of a Lua table of 0-based tet indices; returns their mass (kg).
-- Node and tet indices change (nodes no kept tet holds go, the rest are renumbered in order).
function World:remove_tets(body, tets)
  local removed = ffi.new("double[1]")
  local list = #tets > 0 and ffi.new("int32_t[?]", #tets, tets) or nil
  self:check(C.mica_body_remove_tets(self.ptr, body, list, #tets, removed))
  return removed[0]
end

-- The numbers of a (nested) Lua table in order: {x1, y1, z1, ...} stays as it is, a table of
-- triangles {{{x, y, z}, {x, y, z}, {x, y, z}}, ...} or of rows of 9 is flattened.
local function flatten(values, out)
  for _, v in ipairs(values) do
    if type(v) == "table" then flatten(v, out) else out[#out + 1] = v end
  end
  return out
end

-- Incision (since 0.8): separates the body along a cut surface, triangles in world space (m) where
-- the body is now: a Lua table of 9 numbers a triangle (its three corners), flat or nested.
-- Returns faces_cut, nodes_added; a cut frees no piece of fewer than 8 tets (such a sliver stays
-- joined); node copies are numbered after the body's nodes, tet indices stay (see
-- topology_version).
function World:cut(body, triangles)
  local flat = flatten(triangles, {})
  if #flat % 9 ~= 0 then
    error(string.format("cut triangles: expected 9 values a triangle, got %d", #flat), 0)
  end
  local n = #flat / 9
  local faces, added = ffi.new("int32_t[1]"), ffi.new("int32_t[1]")
  self:check(C.mica_body_cut(self.ptr, body, n > 0 and ffi.new("double[?]", #flat, flat) or nil, n, faces, added))
  return faces[0], added[0]
end

-- Each tet's cutting resistance (since 0.8), a Lua table of one value per tet: the force per metre
-- of blade edge (N/m, >= 0) the tissue bears before a blade (tool_def blade = 1) parts it.
function World:set_cutting_resistance(body, per_tet)
  local counts = ffi.new("int32_t[2]")
  self:check(C.mica_body_get_counts(self.ptr, body, counts, counts + 1, nil))
  local tets = counts[1]
  if type(per_tet) ~= "table" or #per_tet ~= tets then
    error(string.format("cutting_resistance: one value per tet (%d), got %s", tets,
                        type(per_tet) == "table" and #per_tet or "a " .. type(per_tet)), 0)
  end
  self:check(C.mica_body_set_cutting_resistance(self.ptr, body, ffi.new("double[?]", tets, per_tet), tets))
end

-- How many times the body's tets have changed (0 at creation), as a Lua number.
function World:topology_version(body)
  local out = ffi.new("uint64_t[1]")
  self:check(C.mica_body_get_topology_version(self.ptr, body, out))
  return tonumber(out[0])
end

-- Node masses (double[n], kg), strains (double[6 * t]: xx yy zz yz xz xy) and von Mises stress
-- (double[t], Pa) per tet; each returns the array and its item count.
function World:node_masses(body)
  return read_doubles(self, function(out, cap, count)
    return C.mica_body_get_node_masses(self.ptr, body, out, cap, count)
  end, 1)
end
function World:strains(body)
  return read_doubles(self, function(out, cap, count) return C.mica_body_get_strains(self.ptr, body, out, cap, count) end, 6)
end
function World:von_mises(body)
  return read_doubles(self, function(out, cap, count)
    return C.mica_body_get_von_mises(self.ptr, body, out, cap, count)
  end, 1)
end

-- A constraint on `nodes` of `body`: a Lua table of 0-based node indices (then add_lpc(body, nodes,
-- fields)), or an int32_t array and its count, as select_nodes_by_plane returns them.
function World:add_lpc(body, nodes, count, fields)
  if type(nodes) == "table" then
    if type(count) ~= "number" then count, fields = #nodes, count end
    nodes = vec(nodes, count, "add_lpc nodes", "int32_t")
  end
  local id = ffi.new("mica_lpc_id[1]")
  self:check(C.mica_add_lpc(self.ptr, body, nodes, count, M.lpc_def(fields), id))
  return id[0]
end

function World:remove_lpc(lpc) self:check(C.mica_lpc_remove(self.ptr, lpc)) end

-- Picking: holds the nodes of `body` within `radius` (m) of `center` on a handle; with a tool
-- id the handle follows that tool (forceps). Returns the constraint's id.
function World:grab(body, center, radius, tool)
  local id = ffi.new("mica_lpc_id[1]")
  self:check(C.mica_lpc_grab(self.ptr, body, vec(center, 3, "grab center"), radius, tool or C.MICA_NULL_ID, id))
  return id[0]
end

-- Moves a grab's handle: position (m) and unit quaternion {w, x, y, z} (default identity).
function World:set_handle_pose(lpc, position, orientation)
  self:check(C.mica_lpc_set_handle_pose(self.ptr, lpc, vec(position, 3, "set_handle_pose position"),
                                        vec(orientation or IDENTITY, 4, "set_handle_pose orientation")))
end

function World:set_lpc_velocity(lpc, velocity)
  self:check(C.mica_lpc_set_velocity(self.ptr, lpc, vec(velocity, 3, "set_lpc_velocity velocity")))
end

-- Target positions {x1, y1, z1, ...} (m), one per node of the constraint.
function World:set_lpc_targets(lpc, targets)
  assert(#targets % 3 == 0, "targets: 3 values a node")
  self:check(C.mica_lpc_set_targets(self.ptr, lpc, ffi.new("double[?]", #targets, targets), #targets / 3))
end

-- The reaction force (double[3], N) of a constraint in the last step: the force on the holder.
function World:lpc_reaction(lpc)
  local force = ffi.new("double[3]")
  self:check(C.mica_lpc_get_reaction(self.ptr, lpc, force))
  return force
end

function World:teleport_tool(tool, position, orientation)
  self:check(C.mica_tool_teleport(self.ptr, tool, vec(position, 3, "teleport_tool position"),
                                  vec(orientation or IDENTITY, 4, "teleport_tool orientation")))
end

function World:set_tool_pose(tool, position, orientation)
  self:check(C.mica_tool_set_pose(self.ptr, tool, vec(position, 3, "set_tool_pose position"),
                                  vec(orientation or IDENTITY, 4, "set_tool_pose orientation")))
end

-- Force (double[3], N), torque (double[3], N m) and contacts of a tool in the last step.
function World:tool_force(tool)
  local force, torque, contacts = ffi.new("double[3]"), ffi.new("double[3]"), ffi.new("int32_t[1]")
  self:check(C.mica_tool_get_force(self.ptr, tool, force, torque, contacts))
  return force, torque, contacts[0]
end

-- Zero-copy positions: a const double* (3 per node) and the node count. The memory belongs to
-- the world: valid until the next step, and only while the world is alive (keep it referenced).
function World:positions(body)
  local ptr, n = ffi.new("const double*[1]"), ffi.new("int32_t[1]")
  self:check(C.mica_body_positions_view(self.ptr, body, ptr, n))
  return ptr[0], n[0]
end

-- Sets every node's positions (m) or velocities (m/s): a table (or double array) of 3 values a node.
function World:set_positions(body, values)
  assert(#values % 3 == 0, "positions: 3 values a node")
  self:check(C.mica_body_set_positions(self.ptr, body, ffi.new("double[?]", #values, values), #values / 3))
end
function World:set_velocities(body, values)
  assert(#values % 3 == 0, "velocities: 3 values a node")
  self:check(C.mica_body_set_velocities(self.ptr, body, ffi.new("double[?]", #values, values), #values / 3))
end

-- The world's dynamic state as a Lua string (mica_world_save_state), and back.
function World:save_state()
  local size = ffi.new("size_t[1]")
  self:check(C.mica_world_state_size(self.ptr, size))
  local buffer = ffi.new("uint8_t[?]", size[0])
  self:check(C.mica_world_save_state(self.ptr, buffer, size[0]))
  return ffi.string(buffer, size[0])
end
function World:restore_state(state)
  self:check(C.mica_world_restore_state(self.ptr, state, #state))
end

-- Since 0.6: the ids of the world's live objects of one kind (C.MICA_OBJECT_BODY, _LPC, _TOOL,
-- _DEVICE or, since 0.7, _EMBEDDING), in slot order: a uint64_t array (0-based) and its count.
function World:ids(kind)
  local count = ffi.new("int32_t[1]")
  self:check(C.mica_world_get_ids(self.ptr, kind, nil, 0, count))
  local out = ffi.new("uint64_t[?]", math.max(count[0], 1))
  self:check(C.mica_world_get_ids(self.ptr, kind, out, count[0], count))
  return out, count[0]
end

-- Since 0.6: records the session into a file (created or truncated), for mica.replay(): call it
-- on a new world, before anything is added. record_stop() raises if a write failed meanwhile.
function World:record_start(path) self:check(C.mica_world_record_start(self.ptr, path)) end
function World:record_stop() self:check(C.mica_world_record_stop(self.ptr)) end

-- The contacts of the last step: a mica_contact[?] array (0-based) and its count.
function World:contacts()
  local n = ffi.new("int32_t[1]")
  self:check(C.mica_world_get_contacts(self.ptr, nil, 0, n))
  local out = ffi.new("mica_contact[?]", math.max(n[0], 1))
  out[0].struct_size = ffi.sizeof("mica_contact")
  if n[0] > 0 then self:check(C.mica_world_get_contacts(self.ptr, out, n[0], n)) end
  return out, n[0]
end

-- Since 0.7: embedded meshes (docs/embedding.md, "Rendering"). Binds a render mesh to `body`: xyz
-- a table {x1, y1, z1, x2, ...} (m, in the frame of the rest positions), triangles a table of
-- 0-based vertex indices, 3 a triangle (nil: no normals), fields of mica_embedding_def ({ radius =
-- 0.002 }). Returns the embedding's id, its vertex count and the status (MICA_WARN_UNBOUND_VERTICES
-- when some vertices are farther than the radius: mica_world_last_error names them).
function World:embed(body, xyz, triangles, fields)
  assert(#xyz % 3 == 0 and (triangles == nil or #triangles % 3 == 0), "xyz: 3 values a vertex, triangles: 3 indices each")
  local def = ffi.new("mica_embedding_def")
  check(C.mica_embedding_def_init(def, ffi.sizeof(def)), nil)
  fill(def, fields)
  local tris = triangles and #triangles > 0 and ffi.new("int32_t[?]", #triangles, triangles) or nil
  local id = ffi.new("mica_embedding_id[1]")
  local status = self:check(C.mica_embedding_create(self.ptr, body, def, ffi.new("double[?]", #xyz, xyz), #xyz / 3,
                                                    tris, tris and #triangles / 3 or 0, id))
  return id[0], #xyz / 3, status
end

-- Writes the embedding's positions (m) and, with `out_normals`, its unit normals after the last step
-- into double arrays of 3 values a vertex that the host made once (ffi.new("double[?]", 3 * n)) and
-- reuses; an unbound vertex's values are left as they are. Allocates nothing.
function World:update_embedding(embedding, out_xyz, out_normals)
  self:check(C.mica_embedding_update(self.ptr, embedding, out_xyz, out_normals))
end

-- The kind of each vertex (an int32_t array of C.MICA_EMBED_*, 0-based) and the vertex count; and
-- the counts: vertices, inside, projected, unbound.
function World:embedding_kinds(embedding)
  return read_indices(self, function(out, cap, count)
    return C.mica_embedding_get_kinds(self.ptr, embedding, out, cap, count)
  end)
end
function World:embedding_counts(embedding)
  local c = ffi.new("int32_t[4]")
  self:check(C.mica_embedding_get_counts(self.ptr, embedding, c, c + 1, c + 2, c + 3))
  return c[0], c[1], c[2], c[3]
end

function World:destroy_embedding(embedding) self:check(C.mica_embedding_destroy(self.ptr, embedding)) end

-- A device from mica_device_def fields: { tool = tool } drives a tool, { lpc = grab } (since 0.6)
-- moves a grab's handle and renders its reaction, the force on the hand. With `callbacks`, a device
-- whose callbacks are Lua functions: `callbacks` has read_state(state) and
-- write_force(force, torque), optionally open(), close(), info(out); each returns nothing
-- (success) or a mica_status. An error inside one becomes MICA_ERR_DEVICE.
-- LuaJIT callbacks run only on the thread of this Lua state: call mica.C.mica_device_poll()
-- yourself, never mica_device_start() (its servo thread would enter Lua concurrently).
function World:create_device(fields, callbacks)
  local def = M.device_def(fields)
  local tbl
  if callbacks then
    tbl = ffi.new("mica_device_callbacks")
    tbl.struct_size = ffi.sizeof(tbl)
    for _, name in ipairs({ "open", "close", "info", "read_state", "write_force" }) do
      local fn = callbacks[name]
      if fn then
        local wrapped
        if name == "close" then
          wrapped = function() pcall(fn) end
        else
          wrapped = function(_, ...)
            local ok, status = pcall(fn, ...)
            if not ok then return C.MICA_ERR_DEVICE end
            return status or C.MICA_OK
          end
        end
        local cb = ffi.cast(ffi.typeof(tbl[name]), wrapped)
        self.callbacks[#self.callbacks + 1] = cb -- freed by close(), after the device is gone
        tbl[name] = cb
      end
    end
    def.backend = C.MICA_DEVICE_CALLBACKS
    def.callbacks = tbl
  end
  local id = ffi.new("mica_device_id[1]")
  self:check(C.mica_device_create(self.ptr, def, id))
  return id[0]
end

-- Replay ----------------------------------------------------------------------------------

local Replay = {}
Replay.__index = Replay
M.Replay = Replay

-- Since 0.6: opens a recording (World:record_start) to replay it into a world of its own,
-- replay.world (ids are the recorded ones; read it between steps, changing it makes the rest of
-- the replay diverge). The replay is closed by replay:close() or, failing that, by the garbage
-- collector; its world goes with it.
function M.replay(path)
  local out = ffi.new("mica_replay*[1]")
  check(C.mica_replay_open(path, out), nil)
  local self = setmetatable({ ptr = ffi.gc(out[0], C.mica_replay_close) }, Replay)
  -- Not ffi.gc'd: the world is the replay's. It holds the replay, so the replay outlives it.
  self.world = setmetatable({ ptr = C.mica_replay_world(self.ptr), callbacks = {}, replay = self }, World)
  return self
end

-- The next recorded step (with the calls before it), checked against the recording: returns
-- true and the step's status (a warning such as MICA_WARN_NOT_CONVERGED is returned, as by
-- World:step), or false at the end of the recording. Raises a mica.Error: MICA_ERR_DIVERGED
-- when the step does not reproduce the recording (the message names the step),
-- MICA_ERR_TRUNCATED when the recording was cut short (after its whole steps).
function Replay:step()
  assert(self.ptr ~= nil, "the replay is closed")
  local stepped = ffi.new("int32_t[1]")
  local status = check(C.mica_replay_step(self.ptr, stepped), self.world.ptr)
  return stepped[0] ~= 0, status
end

-- Closes the replay and destroys its world now.
function Replay:close()
  if self.ptr ~= nil then
    self.world.ptr = nil
    C.mica_replay_close(ffi.gc(self.ptr, nil))
    self.ptr = nil
  end
end

return M
