-- SPDX-License-Identifier: Apache-2.0
-- Tests of the LuaJIT binding (bindings/luajit): the generated cdef against the header
-- manifest (the drift guard), the sphere-indent scene against the C reference, errors, devices,
-- recording and replay.
-- Environment (tests/bindings/CMakeLists.txt): MICA_LIBRARY, MICA_MANIFEST_TSV, MICA_REFERENCE;
-- LUA_PATH finds mica.lua and the generated mica_cdef.lua.
local ffi = require("ffi")
local mica = require("mica")
local C = mica.C

local passed, failed, skipped = 0, 0, 0

local function test(name, fn)
  local ok, err = pcall(fn)
  if ok and err == "skip" then
    skipped = skipped + 1
    print("SKIP " .. name)
  elseif ok then
    passed = passed + 1
    print("ok   " .. name)
  else
    failed = failed + 1
    print("FAIL " .. name .. ": " .. tostring(err))
  end
end

local function expect(cond, message)
  if not cond then error(message, 2) end
end

-- The manifest: tab-separated rows (see tests/bindings/header_manifest.py).
local manifest = { functions = {}, function_order = {}, structs = {}, struct_order = {}, typedefs = {}, constants = {} }
for line in io.lines(os.getenv("MICA_MANIFEST_TSV")) do
  local row = {}
  for cell in line:gmatch("[^\t]+") do row[#row + 1] = cell end
  local kind = row[1]
  if kind == "function" then
    manifest.functions[row[2]] = tonumber(row[5])
    manifest.function_order[#manifest.function_order + 1] = row[2]
  elseif kind == "struct" then
    manifest.structs[row[2]] = { size = tonumber(row[3]), align = tonumber(row[4]), fields = {} }
    manifest.struct_order[#manifest.struct_order + 1] = row[2]
  elseif kind == "field" then
    local f = manifest.structs[row[2]].fields
    f[#f + 1] = { name = row[3], offset = tonumber(row[4]), size = tonumber(row[5]) }
  elseif kind == "typedef" then
    manifest.typedefs[row[2]] = tonumber(row[3])
  elseif kind == "constant" then
    manifest.constants[row[2]] = tonumber(row[3])
  end
end

-- Function declarations of the cdef string ffi.cdef received: name -> argument count.
local function cdef_functions(cdef)
  local found = {}
  local depth, statement = 0, {}
  for ch in cdef:gmatch(".") do
    if ch == "{" then depth = depth + 1 elseif ch == "}" then depth = depth - 1 end
    if ch == ";" and depth == 0 then
      local s = table.concat(statement):gsub("%s+", " ")
      statement = {}
      if not s:match("^%s*typedef") and not s:match("^%s*static") then
        local name, args = s:match("([%w_]+)%s*(%b())%s*$")
        if name then
          args = args:sub(2, -2)
          local count = 0
          if not args:match("^%s*void%s*$") and args:match("%S") then
            local d = 0
            count = 1
            for c in args:gmatch(".") do
              if c == "(" then d = d + 1 elseif c == ")" then d = d - 1 elseif c == "," and d == 0 then count = count + 1 end
            end
          end
          found[name] = count
        end
      end
    else
      statement[#statement + 1] = ch
    end
  end
  return found
end

test("drift: functions and argument counts", function()
  local declared = cdef_functions(require("mica_cdef"))
  for name, argc in pairs(manifest.functions) do
    expect(declared[name] ~= nil, name .. " is not in the cdef")
    expect(declared[name] == argc, name .. ": " .. declared[name] .. " arguments, the header has " .. argc)
  end
  for name in pairs(declared) do expect(manifest.functions[name], name .. " is not in the header") end
end)

test("drift: every function resolves in the library (device functions may be pending)", function()
  local missing = {}
  for _, name in ipairs(manifest.function_order) do
    if not pcall(function() return C[name] end) then missing[#missing + 1] = name end
  end
  for _, name in ipairs(missing) do
    expect(name:match("^mica_device_"), name .. " is declared but libmica does not export it")
  end
  if #missing > 0 then print("     (not exported yet: " .. table.concat(missing, ", ") .. ")") end
end)

test("drift: struct sizes, alignments and field offsets", function()
  for _, name in ipairs(manifest.struct_order) do
    local s = manifest.structs[name]
    expect(ffi.sizeof(name) == s.size, name .. ": size " .. ffi.sizeof(name) .. ", header " .. s.size)
    expect(ffi.alignof(name) == s.align, name .. ": alignment")
    local value = ffi.new(name)
    for _, f in ipairs(s.fields) do
      local where = name .. "." .. f.name
      expect(ffi.offsetof(name, f.name) == f.offset, where .. ": offset")
      local v = value[f.name]
      if type(v) == "cdata" then expect(ffi.sizeof(v) == f.size, where .. ": size") end
    end
  end
end)

test("drift: typedef sizes and constants", function()
  for name, size in pairs(manifest.typedefs) do expect(ffi.sizeof(name) == size, name) end
  for name, value in pairs(manifest.constants) do
    expect(C[name] == value, name .. " = " .. tostring(C[name]) .. ", header " .. value)
  end
end)

test("defaults come from the library", function()
  local d = mica.world_def()
  expect(d.struct_size == ffi.sizeof("mica_world_def"), "struct_size")
  expect(d.header_version == C.MICA_VERSION_NUMBER, "header_version")
  expect(d.gravity[1] == -9.81, "default gravity")
  expect(math.floor(mica.version() / 10000) == C.MICA_VERSION_MAJOR, "major version")
end)

test("errors raise mica.Error with the library's message", function()
  local world = mica.world()
  local ok, e = pcall(world.create_box, world, { 0, 0, 0 }, { -1, 1, 1 }, { 1, 1, 1 })
  expect(not ok and getmetatable(e) == mica.Error, "an error object")
  expect(e.status == C.MICA_ERR_INVALID_ARGUMENT and e.message:find("hi%[0%]"), tostring(e))
  ok, e = pcall(mica.world, { header_version = (C.MICA_VERSION_MAJOR + 1) * 10000 })
  expect(not ok and e.status == C.MICA_ERR_VERSION_MISMATCH, tostring(e))
  world:close()
  world:close() -- twice is harmless
end)

-- Runs fn (which must raise) and checks the message names the problem: a Lua string or a mica.Error.
local function expect_refused(pattern, fn, ...)
  local ok, err = pcall(fn, ...)
  local message = type(err) == "table" and err.message or tostring(err)
  expect(not ok and message:find(pattern, 1, true), "expected '" .. pattern .. "', got " .. tostring(ok and "no error" or message))
  return err
end

test("a table of the wrong length is refused, naming what and where", function()
  local world = mica.world{ gravity = { 0, 0, 0 } }
  local tool = world:create_tool{ radius = 0.01, position = { 0.1, 0.2, 0.3 } }
  local p, q = ffi.new("double[3]"), ffi.new("double[4]")
  local function pose()
    world:check(C.mica_tool_get_pose(world.ptr, tool, p, q))
    return { p[0], p[1], p[2] }
  end
  local function same(a, b) return a[1] == b[1] and a[2] == b[2] and a[3] == b[3] end
  expect(same(pose(), { 0.1, 0.2, 0.3 }), "a def's position of 3 values is taken as given")
  for _, short in ipairs({ { 0.2 }, { 0.1, 0.2 }, { 0.1, 0.2, 0.3, 0.4 }, {} }) do
    expect_refused("set_tool_pose position: expected 3 values, got " .. #short, world.set_tool_pose, world, tool, short)
  end
  expect_refused("set_tool_pose position[1]: expected a number, got a string", world.set_tool_pose, world, tool,
                 { 0, "y", 0 })
  expect_refused("set_tool_pose orientation: expected 4 values, got 3", world.set_tool_pose, world, tool,
                 { 0, 0.3, 0 }, { 1, 0, 0 })
  expect_refused("set_tool_pose position: expected 3 values, got a number", world.set_tool_pose, world, tool, 0.2)
  expect(same(pose(), { 0.1, 0.2, 0.3 }), "a refused pose leaves the tool where it was")
  world:set_tool_pose(tool, { 0.1, 0.25, 0.3 })
  expect(same(pose(), { 0.1, 0.25, 0.3 }), "a pose of 3 values is taken as given")
  expect_refused("teleport_tool position: expected 3 values, got 1", world.teleport_tool, world, tool, { 0.2 })

  -- A teleport is no sweep: a sphere made inside a box and put above it touches nothing.
  local lift = mica.world{ gravity = { 0, 0, 0 } }
  lift:create_box({ 0, 0, 0 }, { 0.1, 0.1, 0.1 }, { 2, 2, 2 })
  local inside = lift:create_tool{ radius = 0.01, position = { 0.05, 0.05, 0.05 } }
  lift:teleport_tool(inside, { 0.05, 0.2, 0.05 })
  lift:step(0.01)
  local force = ffi.new("double[3]")
  local contacts = ffi.new("int32_t[1]")
  lift:check(C.mica_tool_get_force(lift.ptr, inside, force, nil, contacts))
  expect(force[0] == 0 and force[1] == 0 and force[2] == 0 and contacts[0] == 0, "a teleported tool swept nothing")
  lift:close()

  expect_refused("mica_tool_def.position: expected 3 values, got 1", world.create_tool, world, { position = { 0.5 } })
  expect_refused("mica_tool_def.orientation: expected 4 values, got 2", world.create_tool, world,
                 { orientation = { 1, 0 } })
  expect_refused("mica_world_def.gravity: expected 3 values, got 2", mica.world, { gravity = { 0, -9.81 } })
  expect_refused("mica_lpc_def.direction: expected 2 values, got 1", mica.lpc_def, { direction = { { 1, 0, 0 } } })
  expect_refused("mica_lpc_def.direction[1]: expected 3 values, got 2", mica.lpc_def,
                 { direction = { { 1, 0, 0 }, { 0, 1 } } })
  local d = mica.lpc_def{ direction = { { 1, 0, 0 }, { 0, 1, 0 } } }
  expect(d.direction[0][0] == 1 and d.direction[1][1] == 1 and d.direction[1][0] == 0, "an array of arrays is copied")
  local _, tools = world:ids(C.MICA_OBJECT_TOOL)
  expect(tools == 1, "no tool was made from a refused def")

  expect_refused("create_box cells: expected 3 values, got 2", world.create_box, world, { 0, 0, 0 }, { 1, 1, 1 }, { 2, 2 })
  expect_refused("create_box lo: expected 3 values, got 1", world.create_box, world, { 0 }, { 1, 1, 1 }, { 2, 2, 2 })
  local body = world:create_box({ 0, 0, 0 }, { 1, 1, 1 }, { 1, 1, 1 })
  expect_refused("select_nodes_by_plane normal: expected 3 values, got 2", world.select_nodes_by_plane, world, body,
                 { 0, 0, 0 }, { 0, 1 })
  expect_refused("grab center: expected 3 values, got 4", world.grab, world, body, { 0, 0, 0, 0 }, 0.1)
  local grab = world:grab(body, { 0, 1, 0 }, 0.1)
  expect_refused("set_handle_pose orientation: expected 4 values, got 1", world.set_handle_pose, world, grab,
                 { 0, 1, 0 }, { 1 })
  expect_refused("set_lpc_velocity velocity: expected 3 values, got 0", world.set_lpc_velocity, world, grab, {})
  world:close()
end)

test("add_lpc takes a Lua table of nodes", function()
  local world = mica.world{ gravity = { 0, 0, 0 } }
  local body = world:create_box({ 0, 0, 0 }, { 1, 1, 1 }, { 1, 1, 1 })
  local function nodes_of(lpc)
    local out, n = ffi.new("int32_t[8]"), ffi.new("int32_t[1]")
    world:check(C.mica_lpc_get_nodes(world.ptr, lpc, out, 8, n))
    local list = {}
    for i = 0, n[0] - 1 do list[#list + 1] = out[i] end
    table.sort(list)
    return table.concat(list, " ")
  end
  expect(nodes_of(world:add_lpc(body, { 4, 0, 2 })) == "0 2 4", "the nodes of a table")
  local plane = world:add_lpc(body, { 1, 3 }, { kind = C.MICA_LPC_PLANE, direction = { { 0, 1, 0 }, { 0, 0, 0 } } })
  expect(nodes_of(plane) == "1 3", "a table of nodes and the def's fields")
  local bottom, n = world:select_nodes_by_plane(body, { 0, 0, 0 }, { 0, 1, 0 })
  expect(nodes_of(world:add_lpc(body, bottom, n)) ~= "", "an int32_t array and its count, as before")
  expect_refused("add_lpc nodes: expected 3 values, got 2", world.add_lpc, world, body, { 5, 6 }, 3)
  expect_refused("add_lpc nodes[1]: expected a number, got a string", world.add_lpc, world, body, { 5, "6" })
  world:close()
end)

test("a closed world says so", function()
  local world = mica.world()
  local body = world:create_box({ 0, 0, 0 }, { 1, 1, 1 }, { 1, 1, 1 })
  expect(not world:closed(), "an open world")
  world:close()
  expect(world:closed(), "closed")
  local err = expect_refused("the world is closed", world.step, world, 0.01)
  expect(getmetatable(err) == mica.Error and err.status == C.MICA_ERR_WRONG_STATE, "a mica.Error, MICA_ERR_WRONG_STATE")
  expect_refused("the world is closed", world.positions, world, body)
  expect_refused("the world is closed", world.create_tool, world, { radius = 0.01 })
  world:close() -- closing again is harmless
end)

test("positions view is zero-copy", function()
  local world = mica.world()
  local body = world:create_box({ 0, 0, 0 }, { 1, 1, 1 }, { 2, 2, 2 })
  local p, n = world:positions(body)
  local copy, count = ffi.new("double[?]", 3 * n), ffi.new("int32_t[1]")
  world:check(C.mica_body_get_positions(world.ptr, body, copy, n, count))
  for i = 0, 3 * n - 1 do expect(p[i] == copy[i], "view vs copy") end
  local p2 = world:positions(body)
  expect(p == p2, "the same memory")
  world:close()
end)

test("sphere indent matches C to 1e-9", function()
  local ref = {}
  for line in io.lines(os.getenv("MICA_REFERENCE")) do
    local k, fx, fy, fz, contacts = line:match("^(%d+),([^,]+),([^,]+),([^,]+),(%d+)$")
    ref[#ref + 1] = { tonumber(fx), tonumber(fy), tonumber(fz), contacts = tonumber(contacts) }
  end
  -- examples_c/sphere_indent.c, the same operations in the same order.
  local L, E, nu, rho, dt = 0.1, 1e4, 0.4, 1000.0, 0.01
  local R, margin, start_gap, max_depth = 0.02, 0.0015, 0.005, 0.015
  local cells = 12
  local steps = #ref
  local world = mica.world{ gravity = { 0, 0, 0 }, solver = C.MICA_SOLVER_MICA, max_iterations = 2000, tolerance = 1e-6 }
  local cube = world:create_box({ -L / 2, 0, -L / 2 }, { L / 2, L, L / 2 }, { cells, cells, cells }, 5,
    { youngs_modulus = E, poisson_ratio = nu, density = rho, rayleigh_alpha = 2.0, rayleigh_beta = 0.005 })
  local bottom, count = world:select_nodes_by_plane(cube, { 0, 0, 0 }, { 0, 1, 0 }, 1e-9, true)
  world:add_lpc(cube, bottom, count, { kind = C.MICA_LPC_FIXED })
  local y_start = L + R + start_gap
  local sphere = world:create_tool{ shape = C.MICA_TOOL_SPHERE, radius = R, margin = margin, position = { 0, y_start, 0 } }
  local n_load, n_hold, n_unload = math.floor(steps / 3), math.floor(steps / 6), math.floor(steps / 3)
  local travel = start_gap + max_depth
  local speed = travel / (n_load * dt)
  local worst = 0
  for k = 1, steps do
    local y
    if k <= n_load then
      y = y_start - speed * k * dt
    elseif k <= n_load + n_hold then
      y = y_start - travel
    elseif k <= n_load + n_hold + n_unload then
      y = y_start - travel + speed * (k - n_load - n_hold) * dt
    else
      y = y_start
    end
    world:set_tool_pose(sphere, { 0, y, 0 })
    world:step(dt)
    local f, _, contacts = world:tool_force(sphere)
    local r = ref[k]
    expect(contacts == r.contacts, "step " .. k .. ": contacts")
    local scale = math.max(math.sqrt(f[0] ^ 2 + f[1] ^ 2 + f[2] ^ 2), math.sqrt(r[1] ^ 2 + r[2] ^ 2 + r[3] ^ 2))
    for i = 0, 2 do
      local d = math.abs(f[i] - r[i + 1])
      expect(d <= 1e-9 * scale, string.format("step %d: force[%d] %.17g vs C %.17g", k, i, f[i], r[i + 1]))
      if scale > 0 then worst = math.max(worst, d / scale) end
    end
  end
  print(string.format("     (%d steps, largest deviation from C %.3g of the force)", steps, worst))
  world:close()
end)

test("a device with Lua callbacks", function()
  if not pcall(function() return C.mica_device_create end) then return "skip" end
  local world = mica.world{ gravity = { 0, 0, 0 }, solver = C.MICA_SOLVER_MICA }
  local tool = world:create_tool{ radius = 0.02, position = { 0, 0.2, 0 } }
  local reads, writes, last = 0, 0, nil
  local device = world:create_device({ tool = tool }, {
    read_state = function(state)
      reads = reads + 1
      state.position[1] = 0.1
      state.orientation[0] = 1
      state.timestamp = reads * 0.001
    end,
    write_force = function(force)
      writes = writes + 1
      last = { force[0], force[1], force[2] }
    end,
  })
  local state, force = ffi.new("mica_device_state"), ffi.new("double[3]")
  state.struct_size = ffi.sizeof(state)
  world:check(C.mica_device_poll(world.ptr, device, state, force))
  expect(reads >= 1 and writes >= 1, "a read and a write per poll")
  expect(state.position[1] == 0.1, "the state read")
  expect(last[1] == force[0] and last[2] == force[1] and last[3] == force[2], "the force sent is returned")
  world:check(C.mica_device_destroy(world.ptr, device))
  world:close()
end)

test("a device driving a grasp (mica_device_def.lpc, since 0.6)", function()
  if not pcall(function() return C.mica_device_create end) then return "skip" end
  local world = mica.world{ gravity = { 0, 0, 0 }, solver = C.MICA_SOLVER_MICA }
  local body = world:create_box({ -0.05, 0, -0.05 }, { 0.05, 0.1, 0.05 }, { 4, 4, 4 })
  local bottom, n = world:select_nodes_by_plane(body, { 0, 0, 0 }, { 0, 1, 0 })
  local base = world:add_lpc(body, bottom, n)
  local grasp = world:grab(body, { 0, 0.1, 0 }, 0.001)
  local reads = 0
  local device = world:create_device({ lpc = grasp }, {
    read_state = function(state) -- held 5 mm above the grab: it lifts the top face
      reads = reads + 1
      state.position[1] = 0.105
      state.orientation[0] = 1
      state.timestamp = reads * 0.001
    end,
    write_force = function() end,
  })
  local force = ffi.new("double[3]")
  for _ = 1, 20 do
    world:check(C.mica_device_poll(world.ptr, device, nil, force))
    world:check(C.mica_step(world.ptr, 0.01))
  end
  world:check(C.mica_device_poll(world.ptr, device, nil, force))
  local reaction, holder = world:lpc_reaction(grasp), world:lpc_reaction(base)
  expect(reaction[1] < 0 and force[1] < 0, "the grasped tissue pulls the hand down, and the device renders it")
  expect(math.abs(holder[1] + reaction[1]) <= 0.05 * math.abs(reaction[1]), "the base holds the block against the grasp")
  expect(C.mica_lpc_remove(world.ptr, grasp) == C.MICA_ERR_WRONG_STATE, "a driven grasp stays while its device lives")
  world:check(C.mica_device_destroy(world.ptr, device))
  world:check(C.mica_lpc_remove(world.ptr, grasp))
  local tool = world:create_tool{ radius = 0.01, position = { 0, 0.3, 0 } }
  local other = world:grab(body, { 0.025, 0.1, 0 }, 0.01)
  local ok, err = pcall(world.create_device, world, { tool = tool, lpc = other })
  expect(not ok and err.status == C.MICA_ERR_INVALID_ARGUMENT, "a tool or a grasp, not both")
  world:close()
end)

test("loaders, grasp and constraint helpers", function()
  local world = mica.world{ gravity = { 0, -9.81, 0 } }
  local mesh = os.getenv("MICA_SOURCE_DIR") .. "/tests/data/cube_v22.msh"
  local cube = world:create_body_from_file(mesh)
  local counts = ffi.new("int32_t[3]")
  world:check(C.mica_body_get_counts(world.ptr, cube, counts, counts + 1, counts + 2))
  expect(counts[0] > 0 and counts[1] > 0, "the mesh's counts")
  local ok, err = pcall(world.create_body_from_file, world, os.getenv("MICA_SOURCE_DIR") .. "/tests/data/no_such.msh")
  expect(not ok and err.status == C.MICA_ERR_IO, "a missing file raises MICA_ERR_IO")
  local tet = world:create_body({ 2, 0, 0, 3, 0, 0, 2, 1, 0, 2, 0, 1 }, { 0, 1, 2, 3 })
  world:destroy_body(tet)

  -- A grab lifted against gravity: the holder feels the body's weight, downward.
  local box = world:create_box({ 0, 0, 0 }, { 0.1, 0.1, 0.1 }, { 2, 2, 2 }, 5)
  local grab = world:grab(box, { 0.05, 0.1, 0.05 }, 0.06)
  for k = 1, 5 do
    world:set_handle_pose(grab, { 0.05, 0.1 + 0.001 * k, 0.05 })
    world:step(0.01)
  end
  expect(world:lpc_reaction(grab)[1] < 0, "the grab's reaction points down")
  world:remove_lpc(grab)
  local bottom, n = world:select_nodes_by_plane(box, { 0, 0, 0 }, { 0, 1, 0 })
  local clamp = world:add_lpc(box, bottom, n)
  world:set_lpc_velocity(clamp, { 0, 0, 0 })
  local targets = {}
  for i = 0, n - 1 do targets[#targets + 1] = 0; targets[#targets + 1] = 0; targets[#targets + 1] = 0 end
  world:set_lpc_targets(clamp, targets)
  world:step(0.01)
  world:remove_lpc(clamp)
  world:close()
end)

test("an embedded mesh follows its body (since 0.7)", function()
  local world = mica.world{ gravity = { 0, 0, 0 } }
  local box = world:create_box({ 0, 0, 0 }, { 0.1, 0.1, 0.1 }, { 2, 2, 2 }, 5)
  local xyz = { 0.05, 0.05, 0.05, 0.02, 0.1, 0.03, 0.08, 0.1, 0.07, 0.03, 0.1, 0.09, 0.05, 0.5, 0.05 }
  local sheet, n, status = world:embed(box, xyz, { 1, 3, 2 }, { radius = 0.001 })
  expect(n == 5 and status == C.MICA_WARN_UNBOUND_VERTICES, "a far vertex is reported unbound")
  expect(world:last_error():find("vertex 4", 1, true), "the warning names the vertex")
  local count, inside, projected, unbound = world:embedding_counts(sheet)
  expect(count == 5 and inside == 4 and projected == 0 and unbound == 1, "counts")
  local kinds = world:embedding_kinds(sheet)
  expect(kinds[0] == C.MICA_EMBED_INSIDE and kinds[4] == C.MICA_EMBED_UNBOUND, "kinds")
  local out, normals = ffi.new("double[?]", 15), ffi.new("double[?]", 15)
  out[12], out[13], out[14] = 7, 7, 7
  local x, nodes = world:positions(box)
  local lifted = {}
  for i = 0, 3 * nodes - 1 do lifted[i + 1] = x[i] + (i % 3 == 1 and 0.01 or 0) end
  world:set_positions(box, lifted)
  world:update_embedding(sheet, out, normals)
  for i = 0, 11 do
    expect(math.abs(out[i] - xyz[i + 1] - (i % 3 == 1 and 0.01 or 0)) < 1e-12, "a bound vertex moves with the body")
  end
  expect(out[12] == 7 and out[13] == 7 and out[14] == 7, "an unbound vertex is left as it was")
  expect(math.abs(normals[4] - 1) < 1e-12, "the top triangle's normal is +y")
  xyz[7] = 0 / 0
  expect_refused("vertex 2 is not finite", world.embed, world, box, xyz)
  world:destroy_embedding(sheet)
  local ok, e = pcall(world.update_embedding, world, sheet, out, nil)
  expect(not ok and e.status == C.MICA_ERR_STALE_ID, "a destroyed embedding is refused")
  world:close()
end)

test("node state, saved state and contacts", function()
  local world = mica.world{ gravity = { 0, -9.81, 0 } }
  local box = world:create_box({ 0, 0, 0 }, { 0.1, 0.1, 0.1 }, { 2, 2, 2 }, 5, { youngs_modulus = 2e4 })
  local bottom, n = world:select_nodes_by_plane(box, { 0, 0, 0 }, { 0, 1, 0 })
  world:add_lpc(box, bottom, n)
  local tool = world:create_tool{ radius = 0.02, position = { 0.05, 0.1205, 0.05 } }
  local nodes = ffi.new("int32_t[1]")
  world:check(C.mica_body_get_counts(world.ptr, box, nodes, nil, nil))
  -- Set and read back.
  local x, n3 = world:positions(box)
  local moved = {}
  for i = 0, 3 * n3 - 1 do moved[i + 1] = x[i] + 1e-4 end
  world:set_positions(box, moved)
  x = world:positions(box)
  for i = 0, 3 * n3 - 1 do expect(x[i] == moved[i + 1], "a position reads back") end
  for i = 1, #moved do moved[i] = moved[i] - 1e-4 end
  world:set_positions(box, moved)
  local zeros = {}
  for i = 1, #moved do zeros[i] = 0 end
  world:set_velocities(box, zeros)
  local ok, err = pcall(world.set_velocities, world, box, { 0, 0, 0 })
  expect(not ok and err.status == C.MICA_ERR_INVALID_ARGUMENT, "a wrong node count raises")
  -- Save, run, restore, run again: the same bits.
  local function run(first)
    local out = {}
    for k = first, first + 9 do
      world:set_tool_pose(tool, { 0.05, 0.1205 - 0.0003 * math.min(k, 15), 0.05 })
      world:step(0.01)
      local p, count = world:positions(box)
      out[#out + 1] = ffi.string(p, 24 * count) .. ffi.string(world:tool_force(tool), 24)
    end
    return table.concat(out)
  end
  run(0)
  local state = world:save_state()
  local a = run(10)
  world:restore_state(state)
  local b = run(10)
  expect(a == b, "the restored run repeats the first bit for bit")
  -- The contacts add up to the tool force.
  local contacts, count = world:contacts()
  local force = world:tool_force(tool)
  expect(count > 0 and force[1] > 0, "the tool is pressing")
  local sum = 0
  for c = 0, count - 1 do
    local k = contacts[c]
    sum = sum + k.normal[1] * k.normal_impulse + k.tangent_impulse[1] + k.curvature_impulse[1]
  end
  expect(math.abs(sum / 0.01 + force[1]) <= 1e-12 * math.abs(force[1]) * count, "the contacts sum to the tool force")
  ok, err = pcall(world.restore_state, world, state:sub(1, #state - 1))
  expect(not ok and err.status == C.MICA_ERR_PARSE, "a truncated state raises MICA_ERR_PARSE")
  world:close()
end)

test("tissue regions, materials and fields", function()
  -- A box held on a uniform stretch eps along x, nu = 0: strain eps and von Mises E eps in every
  -- tet; node masses sum to density x volume; doubling E doubles the stress.
  local eps, E, rho = 1e-3, 2e4, 1100
  local world = mica.world{ gravity = { 0, 0, 0 } }
  local box = world:create_box({ 0, 0, 0 }, { 0.1, 0.05, 0.05 }, { 2, 1, 1 }, 5,
                               { youngs_modulus = E, poisson_ratio = 0, density = rho })
  local tets, t = world:tets(box)
  expect(t == 10 and tets[4 * t - 1] >= 0, "10 tets of 4 nodes")
  local regions = world:tet_regions(box)
  for e = 0, t - 1 do expect(regions[e] == 0, "a box has region 0") end
  local masses, n = world:node_masses(box)
  local total = 0
  for i = 0, n - 1 do total = total + masses[i] end
  expect(math.abs(total - rho * 0.1 * 0.05 * 0.05) < 1e-15, "node masses sum to rho V")
  local all, targets = ffi.new("int32_t[?]", n), {}
  local rest = ffi.new("double[?]", 3 * n)
  world:check(C.mica_body_get_rest_positions(world.ptr, box, rest, n, nil))
  for i = 0, n - 1 do
    all[i] = i
    targets[#targets + 1] = rest[3 * i] * (1 + eps)
    targets[#targets + 1] = rest[3 * i + 1]
    targets[#targets + 1] = rest[3 * i + 2]
  end
  world:set_lpc_targets(world:add_lpc(box, all, n), targets)
  world:step(0.01)
  local strains = world:strains(box)
  local vm = world:von_mises(box)
  for e = 0, t - 1 do
    expect(math.abs(strains[6 * e] - eps) < 1e-12, "strain xx = eps")
    for c = 1, 5 do expect(math.abs(strains[6 * e + c]) < 1e-12, "other strains 0") end
    expect(math.abs(vm[e] - E * eps) < 1e-9 * E * eps, "von Mises = E eps")
  end
  local stiff = {}
  for e = 1, t do stiff[e] = 2 * E end
  world:set_materials(box, stiff)
  vm = world:von_mises(box)
  expect(math.abs(vm[0] - 2 * E * eps) < 1e-9 * E * eps, "twice E, twice the stress")
  local bad = {}
  for e = 1, t do bad[e] = rho end
  bad[4] = -1
  local ok, err = pcall(world.set_materials, world, box, nil, nil, bad)
  expect(not ok and err.status == C.MICA_ERR_INVALID_ARGUMENT and err.message:find("tet 3"), "a bad density names its tet")
  local cube = world:create_body_from_file(os.getenv("MICA_SOURCE_DIR") .. "/tests/data/two_regions_v41.msh",
                                           { translation = { 2, 0, 0 } })
  local r = world:tet_regions(cube)
  local want = { 7, 7, 7, 9, 9, 0 }
  for e = 0, 5 do expect(r[e] == want[e + 1], "Gmsh physical tags") end
  world:close()
end)

test("an incision, cutting resistance and blades (since 0.8)", function()
  -- A 4 x 2 x 2 cell box cut through x = 0.02 by two triangles covering the section: a copy of each
  -- of the section's 3 x 3 nodes, the mass unchanged, the topology version 1.
  local world = mica.world{ gravity = { 0, 0, 0 } }
  expect(mica.body_def().cutting_resistance == 200, "the default cutting resistance")
  expect(mica.tool_def().blade == 0, "not a blade by default")
  local box = world:create_box({ 0, 0, 0 }, { 0.04, 0.02, 0.02 }, { 4, 2, 2 }, 5)
  local counts = ffi.new("int32_t[2]")
  world:check(C.mica_body_get_counts(world.ptr, box, counts, counts + 1, nil))
  local nodes, tets = counts[0], counts[1]
  local function total_mass()
    local m, n = world:node_masses(box)
    local sum = 0
    for i = 0, n - 1 do sum = sum + m[i] end
    return sum
  end
  local mass = total_mass()
  expect(world:topology_version(box) == 0, "version 0 at creation")
  local x, y0, y1, z0, z1 = 0.02, -0.01, 0.03, -0.01, 0.03
  local section = { { { x, y0, z0 }, { x, y1, z0 }, { x, y1, z1 } }, { { x, y0, z0 }, { x, y1, z1 }, { x, y0, z1 } } }
  local faces, added = world:cut(box, {})
  expect(faces == 0 and added == 0 and world:topology_version(box) == 0, "no triangles, no cut")
  faces, added = world:cut(box, section)
  expect(faces == 2 * 2 * 2, "faces cut: " .. faces)
  expect(added == 3 * 3, "nodes added: " .. added)
  world:check(C.mica_body_get_counts(world.ptr, box, counts, counts + 1, nil))
  expect(counts[0] == nodes + 9 and counts[1] == tets, "counts after the cut")
  expect(world:topology_version(box) == 1, "version 1 after the cut")
  expect(math.abs(total_mass() - mass) <= 1e-12 * mass, "the mass stays")
  -- The same section again, flat: nothing more to separate.
  local flat = { x, y0, z0, x, y1, z0, x, y1, z1, x, y0, z0, x, y1, z1, x, y0, z1 }
  faces, added = world:cut(box, flat)
  expect(added == 0 and world:topology_version(box) == 1, "a second cut along the same faces adds nothing")
  expect_refused("cut triangles: expected 9 values a triangle, got 10", world.cut, world, box,
                 { 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 })
  flat[13] = 0 / 0
  local err = expect_refused("triangle 1", world.cut, world, box, flat)
  expect(err.status == C.MICA_ERR_INVALID_ARGUMENT, "a corner not finite: " .. tostring(err))
  expect(world:topology_version(box) == 1, "a refused cut changes nothing")

  -- Cutting resistance per tet: one value a tet, each finite and >= 0.
  local resistance = {}
  for e = 1, tets do resistance[e] = 500 end
  world:set_cutting_resistance(box, resistance)
  expect_refused("cutting_resistance: one value per tet (" .. tets .. "), got 1", world.set_cutting_resistance,
                 world, box, { 500 })
  resistance[8] = -1
  err = expect_refused("tet 7", world.set_cutting_resistance, world, box, resistance)
  expect(err.status == C.MICA_ERR_INVALID_ARGUMENT, tostring(err))
  err = expect_refused("cutting_resistance", world.create_box, world, { 1, 0, 0 }, { 1.04, 0.02, 0.02 }, { 4, 2, 2 }, 5,
                       { cutting_resistance = -1 })
  expect(err.status == C.MICA_ERR_INVALID_ARGUMENT, tostring(err))

  -- A blade is a capsule: accepted as one, refused as a sphere (no tool made).
  local blade = world:create_tool{ shape = C.MICA_TOOL_CAPSULE, radius = 0.0005, half_length = 0.02, blade = 1,
                                   position = { 0.02, 0.05, 0.01 } }
  local ids, n = world:ids(C.MICA_OBJECT_TOOL)
  expect(n == 1 and ids[0] == blade, "the blade was made")
  err = expect_refused("blade", world.create_tool, world, { shape = C.MICA_TOOL_SPHERE, radius = 0.01, blade = 1 })
  expect(err.status == C.MICA_ERR_INVALID_ARGUMENT, tostring(err))
  ids, n = world:ids(C.MICA_OBJECT_TOOL)
  expect(n == 1, "no tool from the refused def")
  world:close()
end)

-- Recording and replay (since 0.6): a box on a fixed base pressed by a sphere, recorded, then
-- replayed bit for bit; world:ids() gives the created ids; a changed fingerprint diverges.
local RECORDED_STEPS = 20

-- Records the session into `path`: returns the ids {body, lpc, tool} and each step's tool force
-- and positions as byte strings.
local function record_session(path)
  local world = mica.world{ gravity = { 0, -9.81, 0 } }
  world:record_start(path)
  local ok, err = pcall(world.record_start, world, path)
  expect(not ok and err.status == C.MICA_ERR_WRONG_STATE, "already recording")
  local box = world:create_box({ 0, 0, 0 }, { 0.1, 0.1, 0.1 }, { 3, 3, 3 }, 5, { youngs_modulus = 2e4 })
  local lpc = world:add_lpc(box, world:select_nodes_by_plane(box, { 0, 0, 0 }, { 0, 1, 0 }))
  local tool = world:create_tool{ radius = 0.02, position = { 0.05, 0.1205, 0.05 } }
  local ids = { [C.MICA_OBJECT_BODY] = box, [C.MICA_OBJECT_LPC] = lpc, [C.MICA_OBJECT_TOOL] = tool }
  for kind, id in pairs(ids) do
    local got, n = world:ids(kind)
    expect(n == 1 and got[0] == id, "the ids of kind " .. kind .. " are the created ones")
  end
  local _, devices = world:ids(C.MICA_OBJECT_DEVICE)
  expect(devices == 0, "no devices")
  local steps = {}
  for k = 1, RECORDED_STEPS do
    world:set_tool_pose(tool, { 0.05, 0.1205 - 0.0003 * k, 0.05 }) -- 6 mm down over the session
    world:step(0.01)
    local p, count = world:positions(box)
    steps[k] = { force = ffi.string(world:tool_force(tool), 24), positions = ffi.string(p, 24 * count) }
  end
  expect(world:tool_force(tool)[1] > 0, "the tool is pressing")
  world:record_stop()
  ok, err = pcall(world.record_stop, world)
  expect(not ok and err.status == C.MICA_ERR_WRONG_STATE, "not recording")
  world:close()
  return ids, steps
end

test("a recorded session replays bit for bit, with the recorded ids", function()
  local path = os.tmpname()
  local ids, steps = record_session(path)
  local replay = mica.replay(path)
  local world = replay.world
  local _, bodies = world:ids(C.MICA_OBJECT_BODY)
  expect(bodies == 0, "the recorded calls come with the steps")
  local box, tool = ids[C.MICA_OBJECT_BODY], ids[C.MICA_OBJECT_TOOL]
  local k = 0
  while replay:step() do
    k = k + 1
    if k == 1 then -- the first step made the recorded creations
      for kind, id in pairs(ids) do
        local got, n = world:ids(kind)
        expect(n == 1 and got[0] == id, "the replay's ids of kind " .. kind .. " are the recorded ones")
      end
    end
    expect(k <= #steps, "no more steps than recorded")
    local p, count = world:positions(box)
    expect(ffi.string(world:tool_force(tool), 24) == steps[k].force, "the tool force of step " .. k)
    expect(ffi.string(p, 24 * count) == steps[k].positions, "the positions of step " .. k)
  end
  expect(k == RECORDED_STEPS, "the step count: " .. k)
  world:close() -- the replay's world is the replay's: this leaves it alone
  expect(not world:closed() and not replay:step(), "the end stays the end")
  replay:close()
  expect(world:closed(), "closing the replay closes its world")
  replay:close() -- twice is harmless
  os.remove(path)
end)

test("a changed fingerprint diverges at its step", function()
  local path = os.tmpname()
  record_session(path)
  -- The file ends with the last step's fingerprint, then the end entry (24 bytes).
  local f = assert(io.open(path, "r+b"))
  local size = f:seek("end")
  f:seek("set", size - 25)
  local last = f:read(1):byte()
  f:seek("set", size - 25)
  f:write(string.char(bit.bxor(last, 1)))
  f:close()
  local replay = mica.replay(path)
  local k = 0
  local ok, err = pcall(function() while replay:step() do k = k + 1 end end)
  expect(not ok and err.status == C.MICA_ERR_DIVERGED and err.name:find("MICA_ERR_DIVERGED"), tostring(err))
  expect(k == RECORDED_STEPS - 1, "the steps before the last replay: " .. k)
  expect(err.message:find("step " .. RECORDED_STEPS), "the message names the step: " .. err.message)
  replay:close()
  os.remove(path)
  ok, err = pcall(mica.replay, path)
  expect(not ok and err.status == C.MICA_ERR_IO, "a missing recording: " .. tostring(err))
end)

print(string.format("%d passed, %d failed, %d skipped", passed, failed, skipped))
os.exit(failed == 0 and 0 or 1)
