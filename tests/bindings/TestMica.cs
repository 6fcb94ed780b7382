// SPDX-License-Identifier: Apache-2.0
// Tests of the C# binding (bindings/csharp/com.libmica.mica/Runtime): its declarations against the
// header manifest (the drift guard), the sphere-indent scene against the C reference, errors,
// the SafeHandle, the log callback, a device backend written in C#, recording and replay.
// Environment (tests/bindings/CMakeLists.txt): MICA_MANIFEST_TSV, MICA_REFERENCE; libmica on
// LD_LIBRARY_PATH.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.IO;
using System.Linq;
using System.Reflection;
using System.Runtime.CompilerServices;
using System.Runtime.InteropServices;
using LibMica;

class Skip : Exception
{
    public Skip(string why) : base(why) { }
}

static class TestMica
{
    static int passed, failed, skipped;

    static void Test(string name, Action body)
    {
        try
        {
            body();
            passed++;
            Console.WriteLine("ok   " + name);
        }
        catch (Skip s)
        {
            skipped++;
            Console.WriteLine("SKIP " + name + ": " + s.Message);
        }
        catch (Exception e)
        {
            failed++;
            Console.WriteLine("FAIL " + name + ": " + e);
        }
    }

    static void Expect(bool condition, string message)
    {
        if (!condition) throw new Exception(message);
    }

    // --- The manifest (tab-separated, see tests/bindings/header_manifest.py)
    class Param { public string Name, Class; public int Size; }
    class Function { public string Name, ReturnClass; public int ReturnSize; public List<Param> Params = new List<Param>(); }
    class Field { public string Name, Class; public int Offset, Size; }
    class Struct { public string Name; public int Size; public List<Field> Fields = new List<Field>(); }

    static readonly Dictionary<string, Function> functions = new Dictionary<string, Function>();
    static readonly Dictionary<string, Struct> structs = new Dictionary<string, Struct>();
    static readonly Dictionary<string, int> callbacks = new Dictionary<string, int>();
    static readonly Dictionary<string, long> constants = new Dictionary<string, long>();

    static void ReadManifest(string path)
    {
        foreach (var line in File.ReadAllLines(path))
        {
            var c = line.Split('\t');
            switch (c[0])
            {
                case "function":
                    functions[c[1]] = new Function { Name = c[1], ReturnClass = c[2], ReturnSize = int.Parse(c[3]) };
                    break;
                case "param":
                    functions[c[1]].Params.Add(new Param { Name = c[3], Class = c[4], Size = int.Parse(c[5]) });
                    break;
                case "struct":
                    structs[c[1]] = new Struct { Name = c[1], Size = int.Parse(c[2]) };
                    break;
                case "field":
                    structs[c[1]].Fields.Add(new Field { Name = c[2], Offset = int.Parse(c[3]), Size = int.Parse(c[4]), Class = c[5] });
                    break;
                case "callback":
                    callbacks[c[1]] = int.Parse(c[2]);
                    break;
                case "constant":
                    constants[c[1]] = long.Parse(c[2], CultureInfo.InvariantCulture);
                    break;
            }
        }
    }

    // (class, size) of a P/Invoke parameter or return type, as the manifest names them.
    static string Classify(Type t, out int size)
    {
        size = IntPtr.Size;
        if (t == typeof(void)) { size = 0; return "void"; }
        if (t.IsByRef || t.IsArray || t.IsPointer || t == typeof(IntPtr) || t == typeof(string) ||
            typeof(SafeHandle).IsAssignableFrom(t))
            return "ptr";
        size = Marshal.SizeOf(t);
        if (t == typeof(double) || t == typeof(float)) return "float";
        if (t == typeof(int) || t == typeof(long) || t == typeof(short) || t == typeof(sbyte)) return "int";
        if (t == typeof(uint) || t == typeof(ulong) || t == typeof(ushort) || t == typeof(byte)) return "uint";
        return "struct";
    }

    static void DriftFunctions()
    {
        var imports = typeof(MicaNative).GetMethods(BindingFlags.Public | BindingFlags.Static)
            .Where(m => (m.Attributes & MethodAttributes.PinvokeImpl) != 0).ToList();
        var names = new HashSet<string>(imports.Select(m => m.Name));
        foreach (var f in functions.Keys) Expect(names.Contains(f), f + " is not declared");
        foreach (var m in imports)
        {
            Function f;
            Expect(functions.TryGetValue(m.Name, out f), m.Name + " is not in the header");
            var ps = m.GetParameters();
            Expect(ps.Length == f.Params.Count, m.Name + ": " + ps.Length + " parameters, the header has " + f.Params.Count);
            int size;
            Expect(Classify(m.ReturnType, out size) == f.ReturnClass && size == f.ReturnSize, m.Name + ": return type");
            for (int i = 0; i < ps.Length; ++i)
            {
                string cls = Classify(ps[i].ParameterType, out size);
                Expect(cls == f.Params[i].Class && size == f.Params[i].Size,
                       string.Format("{0}: parameter {1} ({2}) is {3}/{4}, the header has {5}/{6}", m.Name, i,
                                     f.Params[i].Name, cls, size, f.Params[i].Class, f.Params[i].Size));
            }
            var import = (DllImportAttribute)Attribute.GetCustomAttribute(m, typeof(DllImportAttribute));
            if (import != null)
            {
                Expect(import.CallingConvention == CallingConvention.Cdecl, m.Name + ": Cdecl");
                Expect(import.EntryPoint == null || import.EntryPoint == m.Name, m.Name + ": entry point");
            }
        }
    }

    static void DriftStructs()
    {
        var mirrors = typeof(MicaNative).GetNestedTypes().Where(t => t.IsValueType && t.Name.StartsWith("mica_")).ToList();
        var names = new HashSet<string>(mirrors.Select(t => t.Name));
        foreach (var s in structs.Keys) Expect(names.Contains(s), s + " has no mirror");
        foreach (var t in mirrors)
        {
            Struct s;
            Expect(structs.TryGetValue(t.Name, out s), t.Name + " is not in the header");
            Expect(t.IsLayoutSequential, t.Name + ": sequential layout");
            Expect(Marshal.SizeOf(t) == s.Size, t.Name + ": size " + Marshal.SizeOf(t) + ", header " + s.Size);
            var fields = t.GetFields(BindingFlags.Instance | BindingFlags.Public | BindingFlags.NonPublic)
                .OrderBy(f => (long)Marshal.OffsetOf(t, f.Name)).ToList();
            Expect(string.Join(",", fields.Select(f => f.Name)) == string.Join(",", s.Fields.Select(f => f.Name)),
                   t.Name + ": fields " + string.Join(",", fields.Select(f => f.Name)));
            for (int i = 0; i < fields.Count; ++i)
            {
                var f = fields[i];
                var h = s.Fields[i];
                string where = t.Name + "." + f.Name;
                Expect((int)Marshal.OffsetOf(t, f.Name) == h.Offset, where + ": offset");
                var fixedBuffer = (FixedBufferAttribute)Attribute.GetCustomAttribute(f, typeof(FixedBufferAttribute));
                int size;
                string cls;
                if (fixedBuffer != null)
                {
                    cls = Classify(fixedBuffer.ElementType, out size);
                    size *= fixedBuffer.Length;
                    // Bytes stand for char arrays and for arrays of structs (fixed buffers hold primitives only).
                    if (fixedBuffer.ElementType == typeof(byte) && (h.Class == "char" || h.Class == "struct")) cls = h.Class;
                }
                else
                {
                    cls = Classify(f.FieldType, out size);
                }
                Expect(size == h.Size, where + ": size " + size + ", header " + h.Size);
                Expect(cls == h.Class, where + ": " + cls + ", header " + h.Class);
                Expect(f.FieldType != typeof(bool), where + ": no bool in a blittable struct");
            }
        }
    }

    static void DriftCallbacksAndConstants()
    {
        foreach (var kv in callbacks)
        {
            var d = typeof(MicaNative).GetNestedType(kv.Key);
            Expect(d != null && typeof(Delegate).IsAssignableFrom(d), kv.Key + ": no delegate");
            Expect(d.GetMethod("Invoke").GetParameters().Length == kv.Value, kv.Key + ": parameter count");
            var ufp = (UnmanagedFunctionPointerAttribute)Attribute.GetCustomAttribute(d, typeof(UnmanagedFunctionPointerAttribute));
            Expect(ufp != null && ufp.CallingConvention == CallingConvention.Cdecl, kv.Key + ": Cdecl");
        }
        var mine = typeof(MicaNative).GetFields(BindingFlags.Public | BindingFlags.Static)
            .Where(f => f.IsLiteral && f.Name.StartsWith("MICA_")).ToDictionary(f => f.Name, f => Convert.ToInt64(f.GetRawConstantValue()));
        foreach (var kv in constants)
        {
            Expect(mine.ContainsKey(kv.Key), kv.Key + " is not declared");
            Expect(mine[kv.Key] == kv.Value, kv.Key + " = " + mine[kv.Key] + ", header " + kv.Value);
        }
        foreach (var k in mine.Keys) Expect(constants.ContainsKey(k), k + " is not in the header");
    }

    // --- The scene of examples_c/sphere_indent.c, the same operations in the same order.
    static void SphereIndent()
    {
        var reference = File.ReadAllLines(Environment.GetEnvironmentVariable("MICA_REFERENCE"))
            .Select(l => l.Split(',')).ToList();
        double L = 0.1, E = 1e4, nu = 0.4, rho = 1000.0, dt = 0.01;
        double R = 0.02, margin = 0.0015, start_gap = 0.005, max_depth = 0.015;
        int cells = 12, steps = reference.Count;
        var wdef = Mica.WorldDef();
        unsafe { wdef.gravity[0] = wdef.gravity[1] = wdef.gravity[2] = 0; }
        wdef.solver = MicaNative.MICA_SOLVER_MICA;
        wdef.max_iterations = 2000;
        wdef.tolerance = 1e-6;
        double worst = 0;
        using (var world = new World(wdef))
        {
            var bdef = Mica.BodyDef();
            bdef.youngs_modulus = E;
            bdef.poisson_ratio = nu;
            bdef.density = rho;
            bdef.rayleigh_alpha = 2.0;
            bdef.rayleigh_beta = 0.005;
            var cube = world.CreateBox(new[] { -L / 2, 0, -L / 2 }, new[] { L / 2, L, L / 2 }, new[] { cells, cells, cells }, 5, bdef);
            var bottom = cube.SelectNodesByPlane(new double[] { 0, 0, 0 }, new double[] { 0, 1, 0 }, 1e-9, true);
            var fixedDef = Mica.LpcDef();
            fixedDef.kind = MicaNative.MICA_LPC_FIXED;
            cube.AddLpc(bottom, fixedDef);
            double y_start = L + R + start_gap;
            var tdef = Mica.ToolDef();
            tdef.shape = MicaNative.MICA_TOOL_SPHERE;
            tdef.radius = R;
            tdef.margin = margin;
            unsafe { tdef.position[0] = 0; tdef.position[1] = y_start; tdef.position[2] = 0; }
            var sphere = world.CreateTool(tdef);
            int n_load = steps / 3, n_hold = steps / 6, n_unload = steps / 3;
            double travel = start_gap + max_depth, speed = travel / (n_load * dt);
            for (int k = 1; k <= steps; ++k)
            {
                double y;
                if (k <= n_load) y = y_start - speed * k * dt;
                else if (k <= n_load + n_hold) y = y_start - travel;
                else if (k <= n_load + n_hold + n_unload) y = y_start - travel + speed * (k - n_load - n_hold) * dt;
                else y = y_start;
                sphere.SetPose(new[] { 0, y, 0 }, new double[] { 1, 0, 0, 0 });
                world.Step(dt);
                double[] torque;
                int contacts;
                var f = sphere.GetForce(out torque, out contacts);
                var r = reference[k - 1];
                var rf = new[] { double.Parse(r[1], CultureInfo.InvariantCulture), double.Parse(r[2], CultureInfo.InvariantCulture),
                                 double.Parse(r[3], CultureInfo.InvariantCulture) };
                Expect(contacts == int.Parse(r[4]), "step " + k + ": contacts");
                double scale = Math.Max(Math.Sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]),
                                        Math.Sqrt(rf[0] * rf[0] + rf[1] * rf[1] + rf[2] * rf[2]));
                for (int i = 0; i < 3; ++i)
                {
                    double d = Math.Abs(f[i] - rf[i]);
                    Expect(d <= 1e-9 * scale, string.Format(CultureInfo.InvariantCulture, "step {0}: force[{1}] {2:R} vs C {3:R}", k, i, f[i], rf[i]));
                    if (scale > 0) worst = Math.Max(worst, d / scale);
                }
            }
        }
        Console.WriteLine("     ({0} steps, largest deviation from C {1:G3} of the force)", steps, worst);
    }

    static void Errors()
    {
        var messages = new List<string>();
        var world = new World(Mica.WorldDef(), (level, text) => messages.Add(level + ": " + text));
        try
        {
            world.CreateBox(new double[] { 0, 0, 0 }, new double[] { -1, 1, 1 }, new[] { 1, 1, 1 }, 5, Mica.BodyDef());
            throw new Exception("no exception");
        }
        catch (MicaException e)
        {
            Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT, "status " + e.Status);
            Expect(e.LibraryMessage.Contains("hi[0]"), "message: " + e.LibraryMessage);
        }
        Expect(messages.Count == 1 && messages[0].StartsWith(MicaNative.MICA_LOG_ERROR + ": "), "the log callback: " + string.Join("|", messages));
        var body = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 1, 1, 1 }, new[] { 1, 1, 1 }, 5, Mica.BodyDef());
        body.Destroy();
        try { int n, t, tri; body.GetCounts(out n, out t, out tri); throw new Exception("no exception"); }
        catch (MicaException e) { Expect(e.Status == MicaNative.MICA_ERR_STALE_ID, "stale id: " + e.Status); }
        world.Dispose();
        world.Dispose(); // twice is harmless
        try { world.Step(0.01); throw new Exception("no exception"); }
        catch (ObjectDisposedException) { }
        var def = Mica.WorldDef();
        def.header_version = (uint)((MicaNative.MICA_VERSION_MAJOR + 1) * 10000);
        try { new World(def); throw new Exception("no exception"); }
        catch (MicaException e) { Expect(e.Status == MicaNative.MICA_ERR_VERSION_MISMATCH, "version: " + e.Status); }
    }

    static void DefaultsAndViews()
    {
        var def = Mica.WorldDef();
        unsafe
        {
            Expect(def.struct_size == (uint)sizeof(MicaNative.mica_world_def), "struct_size");
            Expect(def.gravity[1] == -9.81, "default gravity");
        }
        Expect(def.header_version == MicaNative.MICA_VERSION_NUMBER, "header_version");
        Expect(Mica.Version / 10000 == MicaNative.MICA_VERSION_MAJOR, "major version");
        using (var world = new World(def))
        {
            var body = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 1, 1, 1 }, new[] { 2, 2, 2 }, 5, Mica.BodyDef());
            var view = body.Positions();
            var copy = body.GetPositions();
            Expect(view.NodeCount * 3 == copy.Length, "node count");
            for (int i = 0; i < view.NodeCount; ++i)
                for (int a = 0; a < 3; ++a) Expect(view[i, a] == copy[3 * i + a], "view vs copy");
            Expect(world.Step(0.01), "converged");
            view = body.Positions(); // a new view after each step
            Expect(view[0, 1] < 0, "the box falls");
            var tdef = Mica.ToolDef();
            unsafe { tdef.position[2] = 3; }
            var tool = world.CreateTool(tdef);
            double[] p = new double[3], q = new double[4];
            tool.GetPose(p, q);
            Expect(p[2] == 3 && q[0] == 1, "tool pose");
            // Created at a position without unsafe code (double[] and Vector3); the def's is replaced.
            world.CreateTool(tdef, new double[] { 0.5, 2, 0.25 }).GetPose(p, q);
            Expect(p[0] == 0.5 && p[1] == 2 && p[2] == 0.25, "CreateTool(def, position)");
            world.CreateTool(tdef, new System.Numerics.Vector3(1, 2, 3)).GetPose(p, q);
            Expect(p[0] == 1 && p[1] == 2 && p[2] == 3, "CreateTool(def, Vector3)");
            bool refused = false;
            try { world.CreateTool(tdef, new double[] { 0.5 }); } catch (ArgumentException) { refused = true; }
            Expect(refused && world.GetIds(MicaNative.MICA_OBJECT_TOOL).Length == 3, "a position of 1 value is refused");
            var stats = world.GetStats();
            Expect(stats.step_count == 1 && stats.Stage(MicaNative.MICA_STAGE_SOLVE).runs_last_step == 1, "stats");
        }
    }

    // Setting node state, saving and restoring, and the contacts readout.
    static void StateAndContacts()
    {
        var def = Mica.WorldDef();
        using (var world = new World(def))
        {
            var bdef = Mica.BodyDef();
            bdef.youngs_modulus = 2e4;
            var body = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 0.1, 0.1, 0.1 }, new[] { 2, 2, 2 }, 5, bdef);
            var bottom = body.SelectNodesByPlane(new double[] { 0, 0, 0 }, new double[] { 0, 1, 0 }, 1e-9, true);
            var ldef = Mica.LpcDef();
            ulong lpc;
            Mica.Check(MicaNative.mica_add_lpc(world.Handle, body.Id, bottom, bottom.Length, ref ldef, out lpc), world.Handle);
            var tdef = Mica.ToolDef();
            unsafe { tdef.radius = 0.02; tdef.position[0] = 0.05; tdef.position[1] = 0.1205; tdef.position[2] = 0.05; }
            var tool = world.CreateTool(tdef);
            // Set and read back.
            var x = body.GetPositions();
            var moved = (double[])x.Clone();
            for (int i = 0; i < moved.Length; ++i) moved[i] += 1e-4;
            body.SetPositions(moved);
            Expect(body.GetPositions().SequenceEqual(moved), "positions read back");
            body.SetPositions(x);
            body.SetVelocities(new double[x.Length]);
            try
            {
                body.SetVelocities(new double[3]);
                Expect(false, "a wrong node count throws");
            }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT, "MICA_ERR_INVALID_ARGUMENT");
            }
            // Save, run, restore, run again: the same bits.
            Func<int, List<double>> run = first =>
            {
                var record = new List<double>();
                for (int k = first; k < first + 10; ++k)
                {
                    tool.SetPose(new double[] { 0.05, 0.1205 - 0.0003 * Math.Min(k, 15), 0.05 }, new double[] { 1, 0, 0, 0 });
                    world.Step(0.01);
                    record.AddRange(body.GetPositions());
                    record.AddRange(tool.GetForce());
                }
                return record;
            };
            run(0);
            var state = world.SaveState();
            var a = run(10);
            world.RestoreState(state);
            var b = run(10);
            Expect(a.Select(BitConverter.DoubleToInt64Bits).SequenceEqual(b.Select(BitConverter.DoubleToInt64Bits)),
                   "the restored run repeats the first bit for bit");
            // The contacts add up to the tool force.
            var force = tool.GetForce();
            var contacts = world.GetContacts();
            Expect(contacts.Length > 0 && force[1] > 0, "the tool is pressing");
            double sum = 0;
            unsafe
            {
                foreach (var c in contacts)
                {
                    var k = c;
                    sum += k.normal[1] * k.normal_impulse + k.tangent_impulse[1] + k.curvature_impulse[1];
                }
            }
            Expect(Math.Abs(sum / 0.01 + force[1]) <= 1e-12 * Math.Abs(force[1]) * contacts.Length,
                   "the contacts sum to the tool force");
            try
            {
                world.RestoreState(state.Take(state.Length - 1).ToArray());
                Expect(false, "a truncated state throws");
            }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_PARSE, "MICA_ERR_PARSE");
            }
        }
    }

    // A box held on a uniform stretch eps along x, nu = 0: strain eps and von Mises E eps in every
    // tet; node masses sum to density x volume; doubling E doubles the stress; regions of a file.
    static void RegionsMaterialsAndFields()
    {
        double eps = 1e-3, E = 2e4, rho = 1100;
        var wdef = Mica.WorldDef();
        unsafe { wdef.gravity[1] = 0; }
        using (var world = new World(wdef))
        {
            var bdef = Mica.BodyDef();
            bdef.youngs_modulus = E;
            bdef.poisson_ratio = 0;
            bdef.density = rho;
            var box = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 0.1, 0.05, 0.05 }, new[] { 2, 1, 1 }, 5, bdef);
            int nodes, tets, triangles;
            box.GetCounts(out nodes, out tets, out triangles);
            Expect(box.GetTets().Length == 4 * tets, "4 indices a tet");
            Expect(box.GetTetRegions().All(r => r == 0), "a box has region 0");
            Expect(Math.Abs(box.GetNodeMasses().Sum() - rho * 0.1 * 0.05 * 0.05) < 1e-15, "node masses sum to rho V");
            var rest = new double[3 * nodes];
            int count;
            Mica.Check(MicaNative.mica_body_get_rest_positions(world.Handle, box.Id, rest, nodes, out count), world.Handle);
            var all = Enumerable.Range(0, nodes).ToArray();
            var lpc = box.AddLpc(all, Mica.LpcDef());
            var targets = new double[3 * nodes];
            for (int i = 0; i < nodes; ++i)
            {
                targets[3 * i] = rest[3 * i] * (1 + eps);
                targets[3 * i + 1] = rest[3 * i + 1];
                targets[3 * i + 2] = rest[3 * i + 2];
            }
            Mica.Check(MicaNative.mica_lpc_set_targets(world.Handle, lpc.Id, targets, nodes), world.Handle);
            world.Step(0.01);
            var strains = box.GetStrains();
            var vm = box.GetVonMises();
            Expect(strains.Length == 6 * tets && vm.Length == tets, "6 strains and 1 stress a tet");
            for (int e = 0; e < tets; ++e)
            {
                Expect(Math.Abs(strains[6 * e] - eps) < 1e-12, "strain xx = eps");
                for (int c = 1; c < 6; ++c) Expect(Math.Abs(strains[6 * e + c]) < 1e-12, "other strains 0");
                Expect(Math.Abs(vm[e] - E * eps) < 1e-9 * E * eps, "von Mises = E eps");
            }
            box.SetMaterials(Enumerable.Repeat(2 * E, tets).ToArray());
            Expect(Math.Abs(box.GetVonMises()[0] - 2 * E * eps) < 1e-9 * E * eps, "twice E, twice the stress");
            var bad = Enumerable.Repeat(rho, tets).ToArray();
            bad[3] = -1;
            try { box.SetMaterials(null, null, bad); Expect(false, "a negative density raises"); }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT && e.LibraryMessage.Contains("tet 3"), "names tet 3: " + e.LibraryMessage);
            }
            string mesh = Path.Combine(Environment.GetEnvironmentVariable("MICA_SOURCE_DIR"), "tests", "data", "two_regions_v41.msh");
            var fdef = Mica.BodyDef();
            unsafe { fdef.translation[0] = 2; }
            var cube = world.CreateBodyFromFile(mesh, fdef);
            Expect(cube.GetTetRegions().SequenceEqual(new[] { 7, 7, 7, 9, 9, 0 }), "Gmsh physical tags");
        }
    }

    // Incision: a 4 x 2 x 2 cell box cut through x = 0.02 (two triangles covering the section)
    // gets a copy of each of the section's 3 x 3 nodes, its mass unchanged, its topology version 1.
    static void CutAndBlades()
    {
        var wdef = Mica.WorldDef();
        unsafe { wdef.gravity[1] = 0; }
        using (var world = new World(wdef))
        {
            var bdef = Mica.BodyDef();
            Expect(bdef.cutting_resistance == 200, "the default cutting resistance: " + bdef.cutting_resistance);
            var box = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 0.04, 0.02, 0.02 }, new[] { 4, 2, 2 }, 5, bdef);
            int nodes, tets, triangles;
            box.GetCounts(out nodes, out tets, out triangles);
            double mass = box.GetNodeMasses().Sum();
            Expect(box.TopologyVersion == 0, "version 0 at creation");
            double x = 0.02, y0 = -0.01, y1 = 0.03, z0 = -0.01, z1 = 0.03;
            var section = new[] { x, y0, z0, x, y1, z0, x, y1, z1, x, y0, z0, x, y1, z1, x, y0, z1 };
            int faces, added;
            box.Cut(new double[0], out faces, out added);
            Expect(faces == 0 && added == 0 && box.TopologyVersion == 0, "no triangles, no cut");
            box.Cut(section, out faces, out added);
            Expect(faces == 2 * 2 * 2, "faces cut: " + faces);
            Expect(added == 3 * 3, "nodes added: " + added);
            int nodesAfter, tetsAfter;
            box.GetCounts(out nodesAfter, out tetsAfter, out triangles);
            Expect(nodesAfter == nodes + 9 && tetsAfter == tets, "counts after the cut");
            Expect(box.TopologyVersion == 1, "version 1 after the cut: " + box.TopologyVersion);
            double after = box.GetNodeMasses().Sum();
            Expect(Math.Abs(after - mass) <= 1e-12 * mass, "the mass stays: " + after + " vs " + mass);
            try { box.Cut(new double[10], out faces, out added); Expect(false, "10 values are refused"); }
            catch (ArgumentException e) { Expect(e.Message.Contains("9 values a triangle"), e.Message); }
            var bad = (double[])section.Clone();
            bad[12] = double.NaN;
            try { box.Cut(bad, out faces, out added); Expect(false, "a corner not finite raises"); }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT && e.LibraryMessage.Contains("triangle 1"), "names triangle 1: " + e.LibraryMessage);
            }
            Expect(box.TopologyVersion == 1, "a refused cut changes nothing");

            // Cutting resistance per tet: one value a tet, each finite and >= 0.
            box.SetCuttingResistance(Enumerable.Repeat(500.0, tets).ToArray());
            try { box.SetCuttingResistance(new[] { 500.0 }); Expect(false, "one value for many tets is refused"); }
            catch (ArgumentException e) { Expect(e.Message.Contains("one value per tet (" + tets + ")"), e.Message); }
            var negative = Enumerable.Repeat(500.0, tets).ToArray();
            negative[7] = -1;
            try { box.SetCuttingResistance(negative); Expect(false, "a negative resistance raises"); }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT && e.LibraryMessage.Contains("tet 7"), "names tet 7: " + e.LibraryMessage);
            }

            // A blade is a capsule: accepted as one, refused as a sphere.
            var tdef = Mica.ToolDef();
            Expect(tdef.blade == 0, "not a blade by default");
            tdef.shape = MicaNative.MICA_TOOL_CAPSULE;
            tdef.radius = 0.0005;
            tdef.half_length = 0.02;
            tdef.blade = 1;
            var blade = world.CreateTool(tdef, new[] { 0.02, 0.05, 0.01 });
            Expect(world.GetIds(MicaNative.MICA_OBJECT_TOOL).SequenceEqual(new[] { blade.Id }), "the blade was made");
            var sdef = Mica.ToolDef();
            sdef.shape = MicaNative.MICA_TOOL_SPHERE;
            sdef.radius = 0.01;
            sdef.blade = 1;
            try { world.CreateTool(sdef); Expect(false, "a spherical blade is refused"); }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_INVALID_ARGUMENT && e.LibraryMessage.Contains("blade"), "a spherical blade: " + e.LibraryMessage);
            }
            Expect(world.GetIds(MicaNative.MICA_OBJECT_TOOL).Length == 1, "no tool from the refused def");
        }
    }

    // User code in its own assembly: a mesh from a file, and an id from the raw layer wrapped.
    static void LoaderAndRawIds()
    {
        string mesh = Path.Combine(Environment.GetEnvironmentVariable("MICA_SOURCE_DIR"), "tests", "data", "cube_v22.msh");
        using (var world = new World(Mica.WorldDef()))
        {
            var body = world.CreateBodyFromFile(mesh, Mica.BodyDef());
            int nodes, tets, triangles;
            body.GetCounts(out nodes, out tets, out triangles);
            Expect(nodes > 0 && tets > 0 && triangles > 0, "the mesh's counts");
            try { world.CreateBodyFromFile(Path.Combine(Path.GetDirectoryName(mesh), "no_such_mesh.msh"), Mica.BodyDef()); throw new Exception("no exception"); }
            catch (MicaException e) { Expect(e.Status == MicaNative.MICA_ERR_IO, "a missing file: " + e.Status); }

            var tdef = Mica.ToolDef();
            ulong raw;
            Mica.Check(MicaNative.mica_tool_create(world.Handle, ref tdef, out raw), world.Handle);
            var tool = new Tool(world, raw);
            tool.SetPose(new double[] { 0, 2, 0 });
            double[] p = new double[3], q = new double[4];
            tool.GetPose(p, q);
            Expect(p[1] == 2, "a wrapped raw tool id");
            tool.Teleport(new double[] { 0, 3, 0 });
            tool.GetPose(p, q);
            Expect(p[1] == 3, "a teleport puts the tool where it is told");
            var same = new Body(world, body.Id);
            same.GetCounts(out nodes, out tets, out triangles);
            Expect(tets > 0, "a wrapped body id");
        }
    }

    // An embedded mesh (since 0.7): it follows its body into the host's arrays; an unbound vertex is
    // reported and left as it was; NaN is refused by index; a destroyed embedding is detected.
    static void EmbeddedMesh()
    {
        using (var world = new World(Mica.WorldDef()))
        {
            var body = world.CreateBox(new[] { 0.0, 0, 0 }, new[] { 0.1, 0.1, 0.1 }, new[] { 2, 2, 2 }, 5, Mica.BodyDef());
            var xyz = new[] { 0.05, 0.05, 0.05, 0.02, 0.1, 0.03, 0.08, 0.1, 0.07, 0.03, 0.1, 0.09, 0.05, 0.5, 0.05 };
            var def = Mica.EmbeddingDef();
            Expect(def.radius == 0.001, "the default radius");
            var sheet = body.Embed(xyz, new[] { 1, 3, 2 }, def);
            Expect(world.LastStatus == MicaNative.MICA_WARN_UNBOUND_VERTICES, "a far vertex is reported");
            int n, inside, projected, unbound;
            sheet.GetCounts(out n, out inside, out projected, out unbound);
            Expect(n == 5 && inside == 4 && projected == 0 && unbound == 1, "counts");
            Expect(sheet.GetKinds()[4] == MicaNative.MICA_EMBED_UNBOUND, "kinds");
            var x = body.GetPositions();
            for (int i = 1; i < x.Length; i += 3) x[i] += 0.01;
            body.SetPositions(x);
            var outXyz = new double[15];
            var normals = new double[15];
            outXyz[12] = outXyz[13] = outXyz[14] = 7;
            sheet.Update(outXyz, normals);
            for (int i = 0; i < 12; ++i)
                Expect(Math.Abs(outXyz[i] - xyz[i] - (i % 3 == 1 ? 0.01 : 0)) < 1e-12, "a bound vertex follows the body");
            Expect(outXyz[12] == 7 && outXyz[14] == 7, "an unbound vertex is left as it was");
            Expect(Math.Abs(normals[4] - 1) < 1e-12, "the top triangle's normal is +y");
            xyz[7] = double.NaN;
            try
            {
                body.Embed(xyz);
                Expect(false, "NaN was taken");
            }
            catch (MicaException e)
            {
                Expect(e.Message.Contains("vertex 2 is not finite"), e.Message);
            }
            sheet.Destroy();
            try
            {
                sheet.Update(outXyz);
                Expect(false, "a destroyed embedding was updated");
            }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_STALE_ID, "stale id");
            }
        }
    }

    // System.Numerics overloads (MicaNumerics): Vector3 and Quaternion, libmica's (w, x, y, z) mapped.
    static void NumericsOverloads()
    {
        using (var world = new World(Mica.WorldDef()))
        {
            world.SetGravity(new System.Numerics.Vector3(0, 0, -5));
            var body = world.CreateBox(new[] { 0.0, 0, 0 }, new[] { 0.1, 0.1, 0.1 }, new[] { 2, 2, 2 }, 5, Mica.BodyDef());
            var before = body.GetPositions();
            world.Step(0.01);
            var after = body.GetPositions();
            Expect(after[2] < before[2] && Math.Abs(after[1] - before[1]) < 1e-12, "gravity (0, 0, -5) from a Vector3");

            var tool = world.CreateTool(Mica.ToolDef());
            var turn = System.Numerics.Quaternion.CreateFromAxisAngle(System.Numerics.Vector3.UnitY, (float)(Math.PI / 2));
            tool.SetPose(new System.Numerics.Vector3(1, 2, 3), turn);
            double[] p = new double[3], q = new double[4];
            tool.GetPose(p, q);
            Expect(p[0] == 1 && p[1] == 2 && p[2] == 3, "position from a Vector3");
            Expect(Math.Abs(q[0] - turn.W) < 1e-7 && Math.Abs(q[2] - turn.Y) < 1e-7 && q[1] == 0 && q[3] == 0,
                   "orientation from a Quaternion as (w, x, y, z): " + string.Join(", ", q));
            System.Numerics.Vector3 position;
            System.Numerics.Quaternion orientation;
            tool.GetPose(out position, out orientation);
            Expect(position == new System.Numerics.Vector3(1, 2, 3), "position back as a Vector3");
            Expect(Math.Abs(orientation.W - turn.W) < 1e-6 && Math.Abs(orientation.Y - turn.Y) < 1e-6, "orientation back");
            var force = tool.GetForce();
            Expect(tool.GetForceVector() == new System.Numerics.Vector3((float)force[0], (float)force[1], (float)force[2]), "force");

            var nodes = body.SelectNodesByPlane(System.Numerics.Vector3.Zero, System.Numerics.Vector3.UnitZ, 1e-9, true);
            Expect(nodes.Length == 9, "the nodes of z = 0: " + nodes.Length);
            var lpc = body.Grab(new System.Numerics.Vector3(0.1f, 0.1f, 0.1f), 0.01);
            lpc.SetHandlePose(new System.Numerics.Vector3(0.1f, 0.1f, 0.12f), System.Numerics.Quaternion.Identity);
            world.Step(0.01);
            var reaction = lpc.GetReaction();
            var r = lpc.GetReactionVector();
            Expect(r.Z == (float)reaction[2] && reaction[2] != 0, "the reaction as a Vector3: " + reaction[2]);
        }
    }

    sealed class Stylus : DeviceBackend
    {
        public int Reads, Writes, Opened, Closed;
        public double[] LastForce = new double[3];

        public override void Open() { Opened++; }
        public override void Close() { Closed++; }

        public override void ReadState(ref MicaNative.mica_device_state state)
        {
            Reads++;
            unsafe
            {
                // A ref parameter may point into the heap: fixed buffers in it are pinned first.
                fixed (double* p = state.position) p[1] = 0.1;
                fixed (double* q = state.orientation) q[0] = 1;
            }
            state.timestamp = Reads * 0.001;
        }

        public override void WriteForce(double fx, double fy, double fz, double tx, double ty, double tz)
        {
            Writes++;
            LastForce[0] = fx; LastForce[1] = fy; LastForce[2] = fz;
        }
    }

    static void DeviceBackendInCSharp()
    {
        try { Mica.DeviceDef(); }
        catch (EntryPointNotFoundException) { throw new Skip("the loaded libmica has no device functions yet"); }
        using (var world = new World(Mica.WorldDef()))
        {
            var tool = world.CreateTool(Mica.ToolDef());
            var stylus = new Stylus();
            var device = world.CreateDevice(Mica.DeviceDef(), tool, stylus);
            Expect(stylus.Opened == 1, "opened");
            var state = new MicaNative.mica_device_state();
            var force = new double[3];
            Expect(device.Poll(ref state, force) >= 0, "poll");
            Expect(stylus.Reads >= 1 && stylus.Writes >= 1, "a read and a write per poll");
            unsafe { Expect(state.position[1] == 0.1, "the state read"); }
            Expect(force.SequenceEqual(stylus.LastForce), "the force sent is returned");
            device.Destroy();
            Expect(stylus.Closed == 1 && stylus.Error == null, "closed");
        }
    }

    // Recording and replay (since 0.6): a box on a fixed base pressed by a sphere, recorded.
    const int RecordedSteps = 20;

    // Records the session into `path`: the ids by kind, each step's tool force and positions.
    static Dictionary<int, ulong[]> RecordSession(string path, List<double[]> forces, List<double[]> positions)
    {
        var wdef = Mica.WorldDef();
        using (var world = new World(wdef))
        {
            world.RecordStart(path);
            try
            {
                world.RecordStart(path);
                Expect(false, "recording twice throws");
            }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_WRONG_STATE, "already recording");
            }
            var bdef = Mica.BodyDef();
            bdef.youngs_modulus = 2e4;
            var body = world.CreateBox(new double[] { 0, 0, 0 }, new double[] { 0.1, 0.1, 0.1 }, new[] { 3, 3, 3 }, 5, bdef);
            var lpc = body.AddLpc(body.SelectNodesByPlane(new double[] { 0, 0, 0 }, new double[] { 0, 1, 0 }, 1e-9, true),
                                  Mica.LpcDef());
            var tdef = Mica.ToolDef();
            unsafe { tdef.radius = 0.02; tdef.position[0] = 0.05; tdef.position[1] = 0.1205; tdef.position[2] = 0.05; }
            var tool = world.CreateTool(tdef);
            var ids = new Dictionary<int, ulong[]>
            {
                { MicaNative.MICA_OBJECT_BODY, new[] { body.Id } },
                { MicaNative.MICA_OBJECT_LPC, new[] { lpc.Id } },
                { MicaNative.MICA_OBJECT_TOOL, new[] { tool.Id } },
                { MicaNative.MICA_OBJECT_DEVICE, new ulong[0] },
            };
            foreach (var kv in ids)
                Expect(world.GetIds(kv.Key).SequenceEqual(kv.Value), "the ids of kind " + kv.Key + " are the created ones");
            for (int k = 1; k <= RecordedSteps; ++k)
            {
                tool.SetPose(new double[] { 0.05, 0.1205 - 0.0003 * k, 0.05 }); // 6 mm down over the session
                world.Step(0.01);
                forces.Add(tool.GetForce());
                positions.Add(body.GetPositions());
            }
            Expect(forces[forces.Count - 1][1] > 0, "the tool is pressing");
            world.RecordStop();
            try
            {
                world.RecordStop();
                Expect(false, "stopping twice throws");
            }
            catch (MicaException e)
            {
                Expect(e.Status == MicaNative.MICA_ERR_WRONG_STATE, "not recording");
            }
            return ids;
        }
    }

    static bool SameBits(double[] a, double[] b)
    {
        return a.Select(BitConverter.DoubleToInt64Bits).SequenceEqual(b.Select(BitConverter.DoubleToInt64Bits));
    }

    static void RecordAndReplay()
    {
        string path = Path.GetTempFileName();
        try
        {
            var forces = new List<double[]>();
            var positions = new List<double[]>();
            var ids = RecordSession(path, forces, positions);
            World world;
            using (var replay = new Replay(path))
            {
                world = replay.World;
                Expect(world.GetIds(MicaNative.MICA_OBJECT_BODY).Length == 0, "the recorded calls come with the steps");
                Body body = null;
                Tool tool = null;
                int k = 0;
                while (replay.Step())
                {
                    Expect(k < RecordedSteps, "no more steps than recorded");
                    if (k == 0) // the first step made the recorded creations
                    {
                        foreach (var kv in ids)
                            Expect(world.GetIds(kv.Key).SequenceEqual(kv.Value), "the replay's ids of kind " + kv.Key);
                        body = new Body(world, world.GetIds(MicaNative.MICA_OBJECT_BODY)[0]);
                        tool = new Tool(world, world.GetIds(MicaNative.MICA_OBJECT_TOOL)[0]);
                    }
                    Expect(SameBits(tool.GetForce(), forces[k]), "the tool force of step " + (k + 1));
                    Expect(SameBits(body.GetPositions(), positions[k]), "the positions of step " + (k + 1));
                    ++k;
                }
                Expect(k == RecordedSteps, "the step count: " + k);
                world.Dispose(); // the replay's world is the replay's: this leaves it alone
                Expect(!world.IsDisposed && !replay.Step(), "the end stays the end");
            }
            Expect(world.IsDisposed, "disposing the replay disposes its world");
        }
        finally
        {
            File.Delete(path);
        }
    }

    static void ReplayDiverges()
    {
        string path = Path.GetTempFileName();
        try
        {
            RecordSession(path, new List<double[]>(), new List<double[]>());
            // The file ends with the last step's fingerprint, then the end entry (24 bytes).
            var bytes = File.ReadAllBytes(path);
            bytes[bytes.Length - 25] ^= 1;
            File.WriteAllBytes(path, bytes);
            using (var replay = new Replay(path))
            {
                int k = 0;
                try
                {
                    while (replay.Step()) ++k;
                    Expect(false, "a changed fingerprint throws");
                }
                catch (MicaException e)
                {
                    Expect(e.Status == MicaNative.MICA_ERR_DIVERGED, "MICA_ERR_DIVERGED: " + e.Message);
                    Expect(e.LibraryMessage.Contains("step " + RecordedSteps), "the message names the step: " + e.Message);
                }
                Expect(k == RecordedSteps - 1, "the steps before the last replay: " + k);
            }
        }
        finally
        {
            File.Delete(path);
        }
        try
        {
            new Replay(path).Dispose();
            Expect(false, "a missing recording throws");
        }
        catch (MicaException e)
        {
            Expect(e.Status == MicaNative.MICA_ERR_IO, "MICA_ERR_IO: " + e.Message);
        }
    }

    // Since 0.6 (mica_device_def.lpc): the stylus, held at y = 0.1 m, moves the handle of a grab
    // made 5 mm lower and so lifts the top face; it renders the grasp's reaction, the force on the
    // hand: down, toward the tissue.
    static void DeviceDrivesAGrasp()
    {
        try { Mica.DeviceDef(); }
        catch (EntryPointNotFoundException) { throw new Skip("the loaded libmica has no device functions yet"); }
        var wdef = Mica.WorldDef();
        unsafe { wdef.gravity[1] = 0; }
        using (var world = new World(wdef))
        {
            var body = world.CreateBox(new[] { -0.05, 0, -0.05 }, new[] { 0.05, 0.1, 0.05 }, new[] { 4, 4, 4 }, 5, Mica.BodyDef());
            var bottom = body.SelectNodesByPlane(new double[] { 0, 0, 0 }, new double[] { 0, 1, 0 }, 1e-9, true);
            var fixedBase = body.AddLpc(bottom, Mica.LpcDef());
            var grasp = body.Grab(new[] { 0, 0.095, 0 }, 0.006);
            var stylus = new Stylus();
            var device = world.CreateGraspDevice(Mica.DeviceDef(), grasp, stylus);
            var state = new MicaNative.mica_device_state();
            var force = new double[3];
            for (int k = 0; k < 20; ++k)
            {
                Expect(device.Poll(ref state, force) >= 0, "poll");
                world.Step(0.01);
            }
            Expect(device.Poll(ref state, force) >= 0, "poll");
            var reaction = grasp.GetReaction();
            var held = fixedBase.GetReaction();
            Expect(reaction[1] < 0 && force[1] < 0, "pulled down toward the tissue: reaction " + reaction[1] + " N, rendered " + force[1] + " N");
            Expect(Math.Abs(held[1] + reaction[1]) <= 0.05 * Math.Abs(reaction[1]), "the base holds the block against the grasp");
            try { grasp.Remove(); Expect(false, "a driven grasp was removed"); }
            catch (MicaException e) { Expect(e.Status == MicaNative.MICA_ERR_WRONG_STATE, "MICA_ERR_WRONG_STATE"); }
            device.Destroy();
            grasp.Remove();
        }
    }

    static int Main()
    {
        ReadManifest(Environment.GetEnvironmentVariable("MICA_MANIFEST_TSV"));
        Test("drift: functions, parameter types and calling convention", DriftFunctions);
        Test("drift: struct sizes, field offsets, sizes and types", DriftStructs);
        Test("drift: callbacks and constants", DriftCallbacksAndConstants);
        Test("defaults, views and stats", DefaultsAndViews);
        Test("node state, saved state and contacts", StateAndContacts);
        Test("errors, the log callback and the SafeHandle", Errors);
        Test("sphere indent matches C to 1e-9", SphereIndent);
        Test("a device backend in C#", DeviceBackendInCSharp);
        Test("a device driving a grasp", DeviceDrivesAGrasp);
        Test("a mesh file and raw ids, from another assembly", LoaderAndRawIds);
        Test("tissue regions, materials and fields", RegionsMaterialsAndFields);
        Test("an incision, cutting resistance and blades", CutAndBlades);
        Test("System.Numerics Vector3 and Quaternion overloads", NumericsOverloads);
        Test("an embedded mesh follows its body", EmbeddedMesh);
        Test("a recorded session replays bit for bit, with the recorded ids", RecordAndReplay);
        Test("a changed fingerprint diverges at its step", ReplayDiverges);
        Console.WriteLine("{0} passed, {1} failed, {2} skipped", passed, failed, skipped);
        return failed == 0 ? 0 : 1;
    }
}
