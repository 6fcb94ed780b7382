#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# run_csharp.sh <TestMica.cs>: compiles the C# binding (the Unity package's Runtime/) with its
# test using mcs and runs it on mono (exit 77, a skip, without them or the manifest).
set -eu
if ! command -v mcs >/dev/null 2>&1 || ! command -v mono >/dev/null 2>&1; then
  echo "SKIP: mcs or mono not found (Debian packages mono-mcs, mono-runtime)"
  exit 77
fi
if [ ! -f "$MICA_MANIFEST_TSV" ]; then
  echo "SKIP: $MICA_MANIFEST_TSV was not generated (configure found no python3)"
  exit 77
fi
runtime=$MICA_SOURCE_DIR/bindings/csharp/com.libmica.mica/Runtime
# Two assemblies, as Unity builds them: the package's Runtime/ (its asmdef, LibMica) and the
# user's code referencing it, which sees only what the binding makes public.
dll=$MICA_TEST_WORK_DIR/LibMica.dll
exe=$MICA_TEST_WORK_DIR/TestMica.exe
# System.Numerics.Vectors (Vector3, Quaternion: Runtime/MicaNumerics.cs) is part of Unity's .NET
# profiles; on Debian it is the package libmono-system-numerics-vectors4.0-cil.
mcs -nologo -warnaserror+ -unsafe -langversion:7.2 -r:System.Numerics -r:System.Numerics.Vectors -target:library -out:"$dll" "$runtime"/*.cs
mcs -nologo -warnaserror+ -unsafe -langversion:7.2 -r:System.Numerics -r:System.Numerics.Vectors -r:"$dll" -out:"$exe" "$1"
# [DllImport("mica")] resolves to libmica.so on the library path; mono finds LibMica.dll beside the exe.
LD_LIBRARY_PATH=$MICA_LIBRARY_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH} exec mono --debug "$exe"
