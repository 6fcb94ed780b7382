// SPDX-License-Identifier: Apache-2.0
// libmica for C# (Unity, Mono, .NET): a thin object layer over MicaNative.
//
//   var def = Mica.WorldDef();
//   def.solver = MicaNative.MICA_SOLVER_MICA;
//   using (var world = new World(def)) {
//       var cube = world.CreateBox(new[] {-0.05, 0, -0.05}, new[] {0.05, 0.1, 0.05}, new[] {4, 4, 4}, 5, Mica.BodyDef());
//       var tool = world.CreateTool(Mica.ToolDef());
//       world.Step(0.01);
//       var force = tool.GetForce();
//   }
//
// Errors (status < 0) throw MicaException (Status, the library's message). Warnings (status > 0)
// do not throw: Step() returns false when the solver stopped at its cap, and World.LastStatus
// holds the last status.
//
// Lifetime: a World owns a WorldHandle (a SafeHandle); Dispose() destroys the world at once on
// the calling thread, which should be the world's thread. A world never disposed is destroyed
// by the handle's finalizer (on the finalizer thread, when nothing else can use it). A Replay
// owns a ReplayHandle; its World (the replay's world) is borrowed: disposing it does nothing,
// disposing the Replay destroys both.
//
// Callbacks (the log, device backends): IL2CPP can only call back into static methods marked
// [AOT.MonoPInvokeCallback]; instance methods and lambdas crash there. So every callback below
// is a static trampoline, kept in a static delegate field (never collected), and the instance
// it serves travels through the C `user` pointer as a GCHandle, freed with the world.
using System;
using System.Collections.Generic;
using System.Runtime.InteropServices;
using System.Text;
using Microsoft.Win32.SafeHandles;

namespace LibMica
{
    /// <summary>A libmica call failed (status &lt; 0).</summary>
    public class MicaException : Exception
    {
        public readonly int Status;
        public readonly string LibraryMessage;

        public MicaException(int status, string message)
            : base((message.Length > 0 ? message + " " : "") + "(" + Mica.StatusString(status) + ")")
        {
            Status = status;
            LibraryMessage = message;
        }
    }

    /// <summary>Owns a mica_world*: releasing it destroys the world, then frees the GCHandles of
    /// the callbacks registered with it (after the last callback can run).</summary>
    public sealed class WorldHandle : SafeHandleZeroOrMinusOneIsInvalid
    {
        readonly List<GCHandle> pinned = new List<GCHandle>();
        readonly ReplayHandle owner; // a replay's world: the replay owns it, this handle holds the replay

        WorldHandle() : base(true) { }

        // The world of a replay: releasing this handle releases its hold on the replay, which
        // destroys the world when the replay closes (so the world never outlives its replay).
        internal WorldHandle(IntPtr world, ReplayHandle replay) : base(true)
        {
            bool added = false;
            replay.DangerousAddRef(ref added);
            owner = replay;
            SetHandle(world);
        }

        internal IntPtr Keep(object target) { return Adopt(GCHandle.Alloc(target)); }

        internal IntPtr Adopt(GCHandle h)
        {
            lock (pinned) pinned.Add(h);
            return GCHandle.ToIntPtr(h);
        }

        protected override bool ReleaseHandle()
        {
            if (owner != null)
            {
                owner.DangerousRelease();
                return true;
            }
            MicaNative.mica_world_destroy(handle);
            lock (pinned)
            {
                foreach (var h in pinned) h.Free();
                pinned.Clear();
            }
            return true;
        }
    }

    /// <summary>Owns a mica_replay*: releasing it closes the replay and destroys its world (after
    /// the replay's WorldHandle is released too: it holds the replay).</summary>
    public sealed class ReplayHandle : SafeHandleZeroOrMinusOneIsInvalid
    {
        ReplayHandle() : base(true) { }

        protected override bool ReleaseHandle()
        {
            MicaNative.mica_replay_close(handle);
            return true;
        }
    }

    /// <summary>Defaults, status checks and strings.</summary>
    public static unsafe class Mica
    {
        /// <summary>The loaded library's version (major * 10000 + minor * 100 + patch).</summary>
        public static int Version { get { return MicaNative.mica_version(); } }

        public static string StatusString(int status) { return Utf8(MicaNative.mica_status_string(status)); }

        /// <summary>Throws MicaException for status &lt; 0; returns the status otherwise.</summary>
        public static int Check(int status, WorldHandle world)
        {
            if (status >= 0) return status;
            bool added = false;
            try
            {
                IntPtr w = IntPtr.Zero;
                if (world != null && !world.IsClosed) { world.DangerousAddRef(ref added); w = world.DangerousGetHandle(); }
                throw new MicaException(status, Utf8(MicaNative.mica_world_last_error(w)));
            }
            finally
            {
                if (added) world.DangerousRelease();
            }
        }

        // Defaults come from the library's *_init functions with this side's struct size.
        public static MicaNative.mica_world_def WorldDef()
        {
            var d = new MicaNative.mica_world_def();
            Check(MicaNative.mica_world_def_init(ref d, (uint)sizeof(MicaNative.mica_world_def),
                                                 MicaNative.MICA_VERSION_NUMBER), null);
            return d;
        }

        public static MicaNative.mica_body_def BodyDef()
        {
            var d = new MicaNative.mica_body_def();
            Check(MicaNative.mica_body_def_init(ref d, (uint)sizeof(MicaNative.mica_body_def)), null);
            return d;
        }

        public static MicaNative.mica_lpc_def LpcDef()
        {
            var d = new MicaNative.mica_lpc_def();
            Check(MicaNative.mica_lpc_def_init(ref d, (uint)sizeof(MicaNative.mica_lpc_def)), null);
            return d;
        }

        public static MicaNative.mica_tool_def ToolDef()
        {
            var d = new MicaNative.mica_tool_def();
            Check(MicaNative.mica_tool_def_init(ref d, (uint)sizeof(MicaNative.mica_tool_def)), null);
            return d;
        }

        public static MicaNative.mica_device_def DeviceDef()
        {
            var d = new MicaNative.mica_device_def();
            Check(MicaNative.mica_device_def_init(ref d, (uint)sizeof(MicaNative.mica_device_def)), null);
            return d;
        }

        /// <summary>The default embedding def (radius 1 mm). Since 0.7.</summary>
        public static MicaNative.mica_embedding_def EmbeddingDef()
        {
            var d = new MicaNative.mica_embedding_def();
            Check(MicaNative.mica_embedding_def_init(ref d, (uint)sizeof(MicaNative.mica_embedding_def)), null);
            return d;
        }

        /// <summary>A NUL-terminated UTF-8 string (for path parameters).</summary>
        public static byte[] Utf8z(string s)
        {
            var bytes = Encoding.UTF8.GetBytes(s);
            Array.Resize(ref bytes, bytes.Length + 1);
            return bytes;
        }

        /// <summary>A C string (UTF-8) as a managed string; "" for NULL.</summary>
        public static string Utf8(IntPtr p)
        {
            if (p == IntPtr.Zero) return "";
            byte* b = (byte*)p;
            int n = 0;
            while (b[n] != 0) ++n;
            return Encoding.UTF8.GetString(b, n);
        }

        internal static double[] Vec(double[] v, int n, string name)
        {
            if (v == null || v.Length != n) throw new ArgumentException(name + " needs " + n + " values");
            return v;
        }
    }

    /// <summary>A simulation world. Use it from one thread at a time; dispose it on that thread.</summary>
    public sealed class World : IDisposable
    {
        public readonly WorldHandle Handle;
        /// <summary>The status of the last call made through this object (warnings are &gt; 0).</summary>
        public int LastStatus { get; private set; }
        readonly bool borrowed; // a replay's world: Dispose() leaves it to the Replay

        World(WorldHandle handle) { Handle = handle; borrowed = true; }

        internal static World OfReplay(ReplayHandle replay)
        {
            return new World(new WorldHandle(MicaNative.mica_replay_world(replay), replay));
        }

        static readonly MicaNative.mica_log_fn LogTrampoline = OnLog;

        /// <summary>Creates a world from `def` (start from Mica.WorldDef()); `log`, if given,
        /// receives the library's messages (level, text) on the thread that made the call.</summary>
        public World(MicaNative.mica_world_def def, Action<int, string> log = null)
        {
            // The log's GCHandle must exist before the world; the handle owns it afterwards.
            var user = log != null ? GCHandle.Alloc(log) : default(GCHandle);
            if (log != null)
            {
                def.log = Marshal.GetFunctionPointerForDelegate(LogTrampoline);
                def.log_user = GCHandle.ToIntPtr(user);
            }
            int status = MicaNative.mica_world_create(ref def, out Handle);
            if (status < 0)
            {
                if (log != null) user.Free();
                Mica.Check(status, null);
            }
            if (log != null) Handle.Adopt(user);
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_log_fn))]
#endif
        static void OnLog(int level, IntPtr message, IntPtr user)
        {
            try
            {
                var log = (Action<int, string>)GCHandle.FromIntPtr(user).Target;
                if (log != null) log(level, Mica.Utf8(message));
            }
            catch (Exception)
            {
                // Nothing may unwind into C.
            }
        }

        /// <summary>Destroys the world (ids and position views die with it). A replay's world
        /// (Replay.World) is the replay's: this does nothing, Replay.Dispose() destroys it.</summary>
        public void Dispose() { if (!borrowed) Handle.Dispose(); }

        internal void Release() { Handle.Dispose(); }

        public bool IsDisposed { get { return Handle.IsClosed; } }

        internal int Check(int status)
        {
            LastStatus = status;
            return Mica.Check(status, Handle);
        }

        /// <summary>One implicit step of dt seconds. Returns false when an iterative solver stopped
        /// at its cap (MICA_WARN_NOT_CONVERGED: the step is kept). Position views die here.</summary>
        public bool Step(double dt) { return Check(MicaNative.mica_step(Handle, dt)) == MicaNative.MICA_OK; }

        public void SetGravity(double[] gravity)
        {
            Check(MicaNative.mica_world_set_gravity(Handle, Mica.Vec(gravity, 3, "gravity")));
        }

        public MicaNative.mica_world_stats GetStats()
        {
            var s = new MicaNative.mica_world_stats();
            unsafe { s.struct_size = (uint)sizeof(MicaNative.mica_world_stats); }
            Check(MicaNative.mica_world_get_stats(Handle, ref s));
            return s;
        }

        /// <summary>The world's dynamic state (mica_world_save_state), for RestoreState.</summary>
        public byte[] SaveState()
        {
            ulong size;
            Check(MicaNative.mica_world_state_size(Handle, out size));
            var buffer = new byte[size];
            Check(MicaNative.mica_world_save_state(Handle, buffer, size));
            return buffer;
        }

        /// <summary>Puts back a state from SaveState (a world of the same shape); throws with the
        /// world unchanged otherwise.</summary>
        public void RestoreState(byte[] state)
        {
            if (state == null) throw new ArgumentNullException("state");
            Check(MicaNative.mica_world_restore_state(Handle, state, (ulong)state.Length));
        }

        /// <summary>The ids of the live objects of one kind (MICA_OBJECT_BODY, _LPC, _TOOL,
        /// _DEVICE or, since 0.7, _EMBEDDING), in slot order: creation order until one of the kind is destroyed. Since 0.6.</summary>
        public ulong[] GetIds(int kind)
        {
            int n;
            Check(MicaNative.mica_world_get_ids(Handle, kind, null, 0, out n));
            var ids = new ulong[n];
            if (n > 0) Check(MicaNative.mica_world_get_ids(Handle, kind, ids, n, out n));
            return ids;
        }

        /// <summary>Starts recording the world into `path` (created or truncated), for Replay: call
        /// it on a new world, before anything is added. Each step is flushed as it ends. Since 0.6.</summary>
        public void RecordStart(string path)
        {
            if (path == null) throw new ArgumentNullException("path");
            Check(MicaNative.mica_world_record_start(Handle, Mica.Utf8z(path)));
        }

        /// <summary>Stops recording and closes the file; throws (MICA_ERR_IO) if a write failed
        /// during the recording. Disposing the world also closes it. Since 0.6.</summary>
        public void RecordStop() { Check(MicaNative.mica_world_record_stop(Handle)); }

        /// <summary>The contacts of the last step.</summary>
        public MicaNative.mica_contact[] GetContacts()
        {
            int n;
            Check(MicaNative.mica_world_get_contacts(Handle, null, 0, out n));
            var contacts = new MicaNative.mica_contact[n];
            if (n == 0) return contacts;
            unsafe { contacts[0].struct_size = (uint)sizeof(MicaNative.mica_contact); }
            Check(MicaNative.mica_world_get_contacts(Handle, contacts, n, out n));
            return contacts;
        }

        public Body CreateBox(double[] lo, double[] hi, int[] cells, int tetsPerCell, MicaNative.mica_body_def def)
        {
            ulong id;
            Check(MicaNative.mica_body_create_box(Handle, ref def, Mica.Vec(lo, 3, "lo"), Mica.Vec(hi, 3, "hi"), cells,
                                                  tetsPerCell, out id));
            return new Body(this, id);
        }

        /// <summary>A body from nodes (3 doubles each, m) and tets (4 indices each).</summary>
        public Body CreateBody(double[] nodes, int[] tets, MicaNative.mica_body_def def)
        {
            ulong id;
            Check(MicaNative.mica_body_create(Handle, ref def, nodes, nodes.Length / 3, tets, tets.Length / 4, out id));
            return new Body(this, id);
        }

        /// <summary>A body from a mesh file: Gmsh .msh (2.2 or 4.1 ASCII) or a TetGen .node/.ele
        /// pair (either name), as mica_body_create_from_file.</summary>
        public Body CreateBodyFromFile(string path, MicaNative.mica_body_def def)
        {
            if (path == null) throw new ArgumentNullException("path");
            ulong id;
            Check(MicaNative.mica_body_create_from_file(Handle, ref def, Mica.Utf8z(path), out id));
            return new Body(this, id);
        }

        public Tool CreateTool(MicaNative.mica_tool_def def)
        {
            ulong id;
            Check(MicaNative.mica_tool_create(Handle, ref def, out id));
            return new Tool(this, id);
        }

        /// <summary>A tool created at `position` (m, def.position; no unsafe code needed). Create it
        /// where it starts: SetPose moves it along a sweep from its last pose, pushing what lies on the way.</summary>
        public unsafe Tool CreateTool(MicaNative.mica_tool_def def, double[] position)
        {
            Mica.Vec(position, 3, "position");
            for (int i = 0; i < 3; ++i) def.position[i] = position[i];
            return CreateTool(def);
        }

        /// <summary>A device driving `tool`: with a backend, its methods are the callback table;
        /// without, the def's own backend (MICA_DEVICE_NULL by default).</summary>
        public Device CreateDevice(MicaNative.mica_device_def def, Tool tool, DeviceBackend backend = null)
        {
            def.tool = tool != null ? tool.Id : MicaNative.MICA_NULL_ID;
            return CreateDeviceWith(def, backend);
        }

        /// <summary>A device moving the handle of `grasp` (a Grab without a tool; since 0.6,
        /// mica_device_def.lpc): it renders the grasp's reaction, the force the held tissue puts on
        /// the hand.</summary>
        public Device CreateGraspDevice(MicaNative.mica_device_def def, Lpc grasp, DeviceBackend backend = null)
        {
            if (grasp == null) throw new ArgumentNullException("grasp");
            def.tool = MicaNative.MICA_NULL_ID;
            def.lpc = grasp.Id;
            return CreateDeviceWith(def, backend);
        }

        private unsafe Device CreateDeviceWith(MicaNative.mica_device_def def, DeviceBackend backend)
        {
            var table = new MicaNative.mica_device_callbacks();
            if (backend != null)
            {
                table = DeviceBackend.Table(Handle.Keep(backend));
                def.backend = MicaNative.MICA_DEVICE_CALLBACKS;
                def.callbacks = (IntPtr)(&table); // copied by mica_device_create
            }
            ulong id;
            Check(MicaNative.mica_device_create(Handle, ref def, out id));
            return new Device(this, id, backend);
        }

        public void WriteVtk(string path) { Check(MicaNative.mica_world_write_vtk(Handle, Mica.Utf8z(path))); }
    }

    /// <summary>A recording (World.RecordStart) replayed into a world of its own (since 0.6). World
    /// is the replay's world: ids are the recorded ones (wrap them: new Tool(replay.World, id));
    /// read it between steps, changing it makes the rest of the replay diverge. Use the replay
    /// from one thread at a time; Dispose() closes it and destroys its world.</summary>
    public sealed class Replay : IDisposable
    {
        public readonly ReplayHandle Handle;
        public readonly World World;

        /// <summary>Opens a recording; throws MicaException (MICA_ERR_IO, MICA_ERR_PARSE, ...).</summary>
        public Replay(string path)
        {
            if (path == null) throw new ArgumentNullException("path");
            int status = MicaNative.mica_replay_open(Mica.Utf8z(path), out Handle);
            if (status < 0)
            {
                Handle.Dispose();
                Mica.Check(status, null);
            }
            World = World.OfReplay(Handle);
        }

        /// <summary>Makes the recorded calls up to the next step, then that step, and checks its
        /// results against the recording. Returns true when a step was replayed, false at the end
        /// of the recording; World.LastStatus has the step's status (a warning such as
        /// MICA_WARN_NOT_CONVERGED if it had one when recorded). Throws MicaException:
        /// MICA_ERR_DIVERGED when the step does not reproduce the recording (the message names
        /// the step), MICA_ERR_TRUNCATED when the recording was cut short (after its whole
        /// steps), MICA_ERR_PARSE for a corrupt entry.</summary>
        public bool Step()
        {
            int stepped;
            World.Check(MicaNative.mica_replay_step(Handle, out stepped));
            return stepped != 0;
        }

        public void Dispose()
        {
            World.Release();
            Handle.Dispose();
        }

        public bool IsDisposed { get { return Handle.IsClosed; } }
    }

    /// <summary>A body of a world (a 64-bit id plus its world).</summary>
    public sealed class Body
    {
        public readonly World World;
        public readonly ulong Id;

        /// <summary>Wraps a body id of `world` (one the raw MicaNative calls returned).</summary>
        public Body(World world, ulong id) { World = world; Id = id; }

        public void GetCounts(out int nodes, out int tets, out int triangles)
        {
            World.Check(MicaNative.mica_body_get_counts(World.Handle, Id, out nodes, out tets, out triangles));
        }

        /// <summary>Copies the current positions (m) into `into` (3 per node), resized if needed.</summary>
        public double[] GetPositions(double[] into = null)
        {
            int n;
            World.Check(MicaNative.mica_body_get_positions(World.Handle, Id, null, 0, out n));
            if (into == null || into.Length != 3 * n) into = new double[3 * n];
            World.Check(MicaNative.mica_body_get_positions(World.Handle, Id, into, n, out n));
            return into;
        }

        /// <summary>Sets every node's position (m), 3 values a node.</summary>
        public void SetPositions(double[] xyz)
        {
            if (xyz == null) throw new ArgumentNullException("xyz");
            World.Check(MicaNative.mica_body_set_positions(World.Handle, Id, xyz, xyz.Length / 3));
        }

        /// <summary>Sets every node's velocity (m/s), 3 values a node.</summary>
        public void SetVelocities(double[] xyz)
        {
            if (xyz == null) throw new ArgumentNullException("xyz");
            World.Check(MicaNative.mica_body_set_velocities(World.Handle, Id, xyz, xyz.Length / 3));
        }

        /// <summary>Zero-copy view of the positions, owned by the world: valid until the next
        /// Step() or the body's or world's destruction. Take a new one after each step.</summary>
        public PositionsView Positions()
        {
            IntPtr p;
            int n;
            World.Check(MicaNative.mica_body_positions_view(World.Handle, Id, out p, out n));
            return new PositionsView(World, p, n);
        }

        /// <summary>Nodes with (p - point) . normal &lt;= tolerance (m).</summary>
        public int[] SelectNodesByPlane(double[] point, double[] normal, double tolerance, bool useRest)
        {
            int n;
            World.Check(MicaNative.mica_body_select_nodes_by_plane(World.Handle, Id, Mica.Vec(point, 3, "point"),
                                                                   Mica.Vec(normal, 3, "normal"), tolerance,
                                                                   useRest ? 1 : 0, null, 0, out n));
            var nodes = new int[n];
            World.Check(MicaNative.mica_body_select_nodes_by_plane(World.Handle, Id, point, normal, tolerance,
                                                                   useRest ? 1 : 0, nodes, n, out n));
            return nodes;
        }

        /// <summary>The tets, 4 node indices each (0-based).</summary>
        public int[] GetTets()
        {
            int n;
            World.Check(MicaNative.mica_body_get_tets(World.Handle, Id, null, 0, out n));
            var tets = new int[4 * n];
            World.Check(MicaNative.mica_body_get_tets(World.Handle, Id, tets, n, out n));
            return tets;
        }

        /// <summary>Region of each tet: the Gmsh physical tag or TetGen region attribute, else 0.</summary>
        public int[] GetTetRegions()
        {
            int n;
            World.Check(MicaNative.mica_body_get_tet_regions(World.Handle, Id, null, 0, out n));
            var regions = new int[n];
            World.Check(MicaNative.mica_body_get_tet_regions(World.Handle, Id, regions, n, out n));
            return regions;
        }

        /// <summary>Per tet: Young's modulus (Pa), Poisson ratio, density (kg/m^3); null keeps that
        /// property. Rebuilds the body's stiffness, mass and damping.</summary>
        public void SetMaterials(double[] youngsModulus, double[] poissonRatio = null, double[] density = null)
        {
            int nodes, tets, triangles;
            GetCounts(out nodes, out tets, out triangles);
            foreach (var a in new[] { youngsModulus, poissonRatio, density })
                if (a != null && a.Length != tets)
                    throw new ArgumentException("one value per tet (" + tets + "), got " + a.Length);
            World.Check(MicaNative.mica_body_set_materials(World.Handle, Id, youngsModulus, poissonRatio, density, tets));
        }

        /// <summary>Resection: removes these tets and returns their mass (kg). Node and tet indices
        /// change: nodes no kept tet holds go, the rest are renumbered in order (see
        /// TopologyVersion).</summary>
        public double RemoveTets(int[] tets)
        {
            double removed;
            World.Check(MicaNative.mica_body_remove_tets(World.Handle, Id, tets, tets.Length, out removed));
            return removed;
        }

        /// <summary>Incision (since 0.8): separates the body along a cut surface given as triangles
        /// in world space (m) where the body is now, 9 values a triangle (its three corners).
        /// facesCut: the faces cut (those the triangles crossed, less any that stayed joined so as
        /// to free no piece of fewer than 8 tets); nodesAdded: the node copies made, numbered
        /// after the body's nodes (tet indices stay; see TopologyVersion).</summary>
        public void Cut(double[] triangles, out int facesCut, out int nodesAdded)
        {
            if (triangles == null) throw new ArgumentNullException("triangles");
            if (triangles.Length % 9 != 0)
                throw new ArgumentException("triangles: 9 values a triangle, got " + triangles.Length);
            World.Check(MicaNative.mica_body_cut(World.Handle, Id, triangles.Length > 0 ? triangles : null,
                                                 triangles.Length / 9, out facesCut, out nodesAdded));
        }

        /// <summary>Each tet's cutting resistance (since 0.8): the force per metre of blade edge
        /// (N/m, &gt;= 0) the tissue bears before a blade (mica_tool_def.blade = 1) parts it.</summary>
        public void SetCuttingResistance(double[] perTet)
        {
            if (perTet == null) throw new ArgumentNullException("perTet");
            int nodes, tets, triangles;
            GetCounts(out nodes, out tets, out triangles);
            if (perTet.Length != tets)
                throw new ArgumentException("cutting resistance: one value per tet (" + tets + "), got " + perTet.Length);
            World.Check(MicaNative.mica_body_set_cutting_resistance(World.Handle, Id, perTet, tets));
        }

        /// <summary>How many times the body's tets have changed (0 at creation).</summary>
        public ulong TopologyVersion
        {
            get
            {
                ulong version;
                World.Check(MicaNative.mica_body_get_topology_version(World.Handle, Id, out version));
                return version;
            }
        }

        double[] ReadDoubles(Func<double[], int, Tuple<int, int>> call, int width)
        {
            var first = call(null, 0);
            World.Check(first.Item1);
            var values = new double[width * first.Item2];
            World.Check(call(values, first.Item2).Item1);
            return values;
        }

        /// <summary>Mass of each node (kg): the row sums of the mass matrix.</summary>
        public double[] GetNodeMasses()
        {
            return ReadDoubles((o, c) => { int n; int s = MicaNative.mica_body_get_node_masses(World.Handle, Id, o, c, out n); return Tuple.Create(s, n); }, 1);
        }

        /// <summary>Strain of each tet, 6 values: xx, yy, zz, yz, xz, xy (tensor shears), co-rotated.</summary>
        public double[] GetStrains()
        {
            return ReadDoubles((o, c) => { int n; int s = MicaNative.mica_body_get_strains(World.Handle, Id, o, c, out n); return Tuple.Create(s, n); }, 6);
        }

        /// <summary>Von Mises stress of each tet (Pa).</summary>
        public double[] GetVonMises()
        {
            return ReadDoubles((o, c) => { int n; int s = MicaNative.mica_body_get_von_mises(World.Handle, Id, o, c, out n); return Tuple.Create(s, n); }, 1);
        }

        public Lpc AddLpc(int[] nodes, MicaNative.mica_lpc_def def)
        {
            ulong id;
            World.Check(MicaNative.mica_add_lpc(World.Handle, Id, nodes, nodes.Length, ref def, out id));
            return new Lpc(World, id);
        }

        /// <summary>Holds the nodes within `radius` of `center` on a handle (following `tool` if given).</summary>
        public Lpc Grab(double[] center, double radius, Tool tool = null)
        {
            ulong id;
            World.Check(MicaNative.mica_lpc_grab(World.Handle, Id, Mica.Vec(center, 3, "center"), radius,
                                                 tool != null ? tool.Id : MicaNative.MICA_NULL_ID, out id));
            return new Lpc(World, id);
        }

        public void Destroy() { World.Check(MicaNative.mica_body_destroy(World.Handle, Id)); }

        /// <summary>Binds a render mesh to this body (since 0.7): `xyz` 3 values a vertex (m, the rest
        /// frame), `triangles` 3 vertex indices each for the normals (null: none). Vertices farther
        /// than def.radius from the body are unbound: World.LastStatus is then
        /// MICA_WARN_UNBOUND_VERTICES and the world's last error names them.</summary>
        public Embedding Embed(double[] xyz, int[] triangles, MicaNative.mica_embedding_def def)
        {
            if (xyz == null || xyz.Length % 3 != 0) throw new ArgumentException("xyz needs 3 values a vertex");
            if (triangles != null && triangles.Length % 3 != 0) throw new ArgumentException("triangles need 3 indices each");
            ulong id;
            int triangleCount = triangles == null ? 0 : triangles.Length / 3;
            World.Check(MicaNative.mica_embedding_create(World.Handle, Id, ref def, xyz, xyz.Length / 3,
                                                         triangleCount > 0 ? triangles : null, triangleCount, out id));
            return new Embedding(World, id, xyz.Length / 3, triangleCount > 0);
        }

        public Embedding Embed(double[] xyz, int[] triangles = null) { return Embed(xyz, triangles, Mica.EmbeddingDef()); }
    }

    /// <summary>A render mesh bound to a body's tets (Body.Embed, since 0.7): Update() writes its
    /// positions and normals after each step into the host's arrays.</summary>
    public sealed class Embedding
    {
        public readonly World World;
        public readonly ulong Id;
        public readonly int VertexCount;
        public readonly bool HasTriangles;

        public Embedding(World world, ulong id, int vertexCount, bool hasTriangles)
        {
            World = world;
            Id = id;
            VertexCount = vertexCount;
            HasTriangles = hasTriangles;
        }

        /// <summary>Writes the positions (m) and, with `normals`, the unit normals after the last step
        /// into arrays of 3 * VertexCount values the host made once and reuses (an unbound vertex's
        /// values are left as they are). Allocates nothing.</summary>
        public void Update(double[] xyz, double[] normals = null)
        {
            if (xyz == null || xyz.Length != 3 * VertexCount) throw new ArgumentException("xyz needs " + 3 * VertexCount + " values");
            if (normals != null && normals.Length != 3 * VertexCount)
                throw new ArgumentException("normals need " + 3 * VertexCount + " values");
            World.Check(MicaNative.mica_embedding_update(World.Handle, Id, xyz, normals));
        }

        /// <summary>The kind of each vertex: MICA_EMBED_INSIDE, _PROJECTED or _UNBOUND.</summary>
        public int[] GetKinds()
        {
            int n;
            World.Check(MicaNative.mica_embedding_get_kinds(World.Handle, Id, null, 0, out n));
            var kinds = new int[n];
            World.Check(MicaNative.mica_embedding_get_kinds(World.Handle, Id, kinds, n, out n));
            return kinds;
        }

        public void GetCounts(out int vertices, out int inside, out int projected, out int unbound)
        {
            World.Check(MicaNative.mica_embedding_get_counts(World.Handle, Id, out vertices, out inside, out projected,
                                                             out unbound));
        }

        public void Destroy() { World.Check(MicaNative.mica_embedding_destroy(World.Handle, Id)); }
    }

    /// <summary>Positions owned by the world, read in place (see Body.Positions()).</summary>
    public unsafe struct PositionsView
    {
        readonly World world; // keeps the world (and its memory) alive while the view is held
        readonly double* data;
        public readonly int NodeCount;

        internal PositionsView(World world, IntPtr data, int nodeCount)
        {
            this.world = world;
            this.data = (double*)data;
            NodeCount = nodeCount;
        }

        /// <summary>Coordinate `axis` (0..2) of node `node`, in m.</summary>
        public double this[int node, int axis]
        {
            get
            {
                if ((uint)node >= (uint)NodeCount || (uint)axis > 2) throw new IndexOutOfRangeException();
                if (world.IsDisposed) throw new ObjectDisposedException("World");
                return data[3 * node + axis];
            }
        }

        public IntPtr Pointer { get { return (IntPtr)data; } }
    }

    /// <summary>A projection constraint group (fixed nodes, a plane, a grab).</summary>
    public sealed class Lpc
    {
        public readonly World World;
        public readonly ulong Id;

        /// <summary>Wraps a constraint id of `world` (one the raw MicaNative calls returned).</summary>
        public Lpc(World world, ulong id) { World = world; Id = id; }

        public void SetVelocity(double[] v) { World.Check(MicaNative.mica_lpc_set_velocity(World.Handle, Id, Mica.Vec(v, 3, "velocity"))); }

        public void SetHandlePose(double[] position, double[] orientation)
        {
            World.Check(MicaNative.mica_lpc_set_handle_pose(World.Handle, Id, Mica.Vec(position, 3, "position"),
                                                            Mica.Vec(orientation, 4, "orientation")));
        }

        /// <summary>Reaction force (N) of the last step.</summary>
        public double[] GetReaction()
        {
            var f = new double[3];
            World.Check(MicaNative.mica_lpc_get_reaction(World.Handle, Id, f));
            return f;
        }

        public void Remove() { World.Check(MicaNative.mica_lpc_remove(World.Handle, Id)); }
    }

    /// <summary>A kinematic tool: set its pose, read the force the bodies put on it.</summary>
    public sealed class Tool
    {
        public readonly World World;
        public readonly ulong Id;
        static readonly double[] Identity = { 1, 0, 0, 0 };

        /// <summary>Wraps a tool id of `world` (one the raw MicaNative calls returned).</summary>
        public Tool(World world, ulong id) { World = world; Id = id; }

        /// <summary>The pose for the next step, which sweeps the tool there from its last pose.</summary>
        public void SetPose(double[] position, double[] orientation = null)
        {
            World.Check(MicaNative.mica_tool_set_pose(World.Handle, Id, Mica.Vec(position, 3, "position"),
                                                      Mica.Vec(orientation ?? Identity, 4, "orientation")));
        }

        /// <summary>Puts the tool at a pose without a sweep (nothing on the way is pushed).</summary>
        public void Teleport(double[] position, double[] orientation = null)
        {
            World.Check(MicaNative.mica_tool_teleport(World.Handle, Id, Mica.Vec(position, 3, "position"),
                                                      Mica.Vec(orientation ?? Identity, 4, "orientation")));
        }

        /// <summary>The current pose: position (m) and quaternion (w, x, y, z); a tool driven by a
        /// device takes the device's pose at each step.</summary>
        public void GetPose(double[] position, double[] orientation)
        {
            World.Check(MicaNative.mica_tool_get_pose(World.Handle, Id, Mica.Vec(position, 3, "position"),
                                                      Mica.Vec(orientation, 4, "orientation")));
        }

        /// <summary>Force (N) of the last step; torque (N m) and contacts through the overload.</summary>
        public double[] GetForce()
        {
            double[] torque;
            int contacts;
            return GetForce(out torque, out contacts);
        }

        public double[] GetForce(out double[] torque, out int contacts)
        {
            var f = new double[3];
            torque = new double[3];
            World.Check(MicaNative.mica_tool_get_force(World.Handle, Id, f, torque, out contacts));
            return f;
        }

        public void Destroy() { World.Check(MicaNative.mica_tool_destroy(World.Handle, Id)); }
    }

    /// <summary>A haptic device implemented in C#: override ReadState and WriteForce (and Open,
    /// Close, Info). ReadState and WriteForce run on the servo thread (Device.Poll's caller or
    /// libmica's 1 kHz thread after Device.Start()): do not allocate there, or the GC will
    /// show in the force. An exception becomes MICA_ERR_DEVICE and is kept in Error.</summary>
    public abstract unsafe class DeviceBackend
    {
        public Exception Error;

        public virtual void Open() { }
        public virtual void Close() { }
        /// <summary>Fill `info`; return false to let libmica assume its defaults.</summary>
        public virtual bool Info(ref MicaNative.mica_device_info info) { return false; }
        public abstract void ReadState(ref MicaNative.mica_device_state state);
        public abstract void WriteForce(double fx, double fy, double fz, double tx, double ty, double tz);

        // Static trampolines (IL2CPP), kept alive by these static fields for the process's life.
        static readonly MicaNative.mica_device_open_fn OpenFn = OnOpen;
        static readonly MicaNative.mica_device_close_fn CloseFn = OnClose;
        static readonly MicaNative.mica_device_info_fn InfoFn = OnInfo;
        static readonly MicaNative.mica_device_read_state_fn ReadStateFn = OnReadState;
        static readonly MicaNative.mica_device_write_force_fn WriteForceFn = OnWriteForce;

        internal static MicaNative.mica_device_callbacks Table(IntPtr user)
        {
            var t = new MicaNative.mica_device_callbacks();
            t.struct_size = (uint)sizeof(MicaNative.mica_device_callbacks);
            t.user = user;
            t.open = Marshal.GetFunctionPointerForDelegate(OpenFn);
            t.close = Marshal.GetFunctionPointerForDelegate(CloseFn);
            t.info = Marshal.GetFunctionPointerForDelegate(InfoFn);
            t.read_state = Marshal.GetFunctionPointerForDelegate(ReadStateFn);
            t.write_force = Marshal.GetFunctionPointerForDelegate(WriteForceFn);
            return t;
        }

        static DeviceBackend From(IntPtr user) { return (DeviceBackend)GCHandle.FromIntPtr(user).Target; }

        static int Fail(DeviceBackend b, Exception e)
        {
            if (b != null) b.Error = e;
            return MicaNative.MICA_ERR_DEVICE;
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_device_open_fn))]
#endif
        static int OnOpen(IntPtr user)
        {
            DeviceBackend b = null;
            try { b = From(user); b.Open(); return MicaNative.MICA_OK; }
            catch (Exception e) { return Fail(b, e); }
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_device_close_fn))]
#endif
        static void OnClose(IntPtr user)
        {
            DeviceBackend b = null;
            try { b = From(user); b.Close(); }
            catch (Exception e) { Fail(b, e); }
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_device_info_fn))]
#endif
        static int OnInfo(IntPtr user, MicaNative.mica_device_info* info)
        {
            DeviceBackend b = null;
            try
            {
                b = From(user);
                var copy = *info;
                if (b.Info(ref copy)) *info = copy;
                return MicaNative.MICA_OK;
            }
            catch (Exception e) { return Fail(b, e); }
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_device_read_state_fn))]
#endif
        static int OnReadState(IntPtr user, MicaNative.mica_device_state* state)
        {
            DeviceBackend b = null;
            try { b = From(user); b.ReadState(ref *state); return MicaNative.MICA_OK; }
            catch (Exception e) { return Fail(b, e); }
        }

#if UNITY_5_3_OR_NEWER
        [AOT.MonoPInvokeCallback(typeof(MicaNative.mica_device_write_force_fn))]
#endif
        static int OnWriteForce(IntPtr user, double* force, double* torque)
        {
            DeviceBackend b = null;
            try
            {
                b = From(user);
                b.WriteForce(force[0], force[1], force[2], torque[0], torque[1], torque[2]);
                return MicaNative.MICA_OK;
            }
            catch (Exception e) { return Fail(b, e); }
        }
    }

    /// <summary>A haptic device driving a tool; Poll() is one servo cycle (servo thread only).</summary>
    public sealed class Device
    {
        public readonly World World;
        public readonly ulong Id;
        public readonly DeviceBackend Backend; // the world's handle keeps it alive for the callbacks

        internal Device(World world, ulong id, DeviceBackend backend) { World = world; Id = id; Backend = backend; }

        /// <summary>One servo cycle: the state read, and the force sent (device frame, N) in `force`.
        /// Returns the status instead of throwing: a failing device (MICA_ERR_DEVICE, zero force
        /// sent) is a normal event at 1 kHz, and the world's error message belongs to the
        /// simulation thread.</summary>
        public unsafe int Poll(ref MicaNative.mica_device_state state, double[] force)
        {
            state.struct_size = (uint)sizeof(MicaNative.mica_device_state);
            return MicaNative.mica_device_poll(World.Handle, Id, ref state, Mica.Vec(force, 3, "force"));
        }

        public void Start() { World.Check(MicaNative.mica_device_start(World.Handle, Id)); }
        public void Stop() { World.Check(MicaNative.mica_device_stop(World.Handle, Id)); }

        public unsafe MicaNative.mica_device_info GetInfo()
        {
            var i = new MicaNative.mica_device_info();
            i.struct_size = (uint)sizeof(MicaNative.mica_device_info);
            World.Check(MicaNative.mica_device_get_info(World.Handle, Id, ref i));
            return i;
        }

        public unsafe MicaNative.mica_device_stats GetStats()
        {
            var s = new MicaNative.mica_device_stats();
            s.struct_size = (uint)sizeof(MicaNative.mica_device_stats);
            World.Check(MicaNative.mica_device_get_stats(World.Handle, Id, ref s));
            return s;
        }

        public void Destroy() { World.Check(MicaNative.mica_device_destroy(World.Handle, Id)); }
    }
}
