// Seiche's public C++ API in one include (link Seiche::seiche; docs/api.md has an example):
//
//   load a scene     scene_loader.hpp   load_scene_file(path, overrides), load_scene_text(json text,
//                                       source name, overrides): a checked SceneDef, or SceneError
//                                       naming the file, the JSON path and the problem
//                    scene.hpp          SceneDef: the scene as data (a scene can also be built in code)
//                    memory_estimate.hpp  check_scene_memory, check_scene_work: the CLI's bounds
//   step             simulation.hpp     Simulation(scene).step_frame(): one frame, its FrameMetrics
//                    frame_metrics.hpp  FrameMetrics: energies, constraint errors, health
//                    thread_count.hpp   run_with_threads(n, work): work on exactly n threads
//   read particles   particle_store.hpp Simulation::particles(): the structure-of-arrays store; a
//                                       column by name with find("x"), or the members x, y, z, vx,
//                                       vy, vz, id, ... (the store is reordered every substep: id
//                                       is each particle's creation index)
//   write frames     output_files.hpp   encode_particles_ply, frame_file_name, write_file_atomically
//                    frame_exporter.hpp FrameExporter, family_exporters (each cloth's OBJ)
//                    runner.hpp         run_scene: what `seiche run` does (frames, report, summary)
//   bake             bake.hpp           bake_scene with make_bake_recipe: what `seiche bake` does
//                    export/scene_exporters.hpp  scene_exporters: the .vdb/.obj/cloth exporters a bake runs
//                    checkpoint.hpp     the checkpoint a bake resumes from
//   measure          bench.hpp          run_bench: error against run time (`seiche bench`)
//                    stability.hpp      the stability suite (`seiche bench --stability`)
//
// Errors are exceptions: SceneError and ResumeError (bad input), BenchError, ExportUnavailableError,
// IoError (a file could not be written), SimulationError (NaN or inf).
#pragma once

#include "seiche/bake.hpp"
#include "seiche/bench.hpp"
#include "seiche/checkpoint.hpp"
#include "seiche/export/scene_exporters.hpp"
#include "seiche/frame_exporter.hpp"
#include "seiche/frame_metrics.hpp"
#include "seiche/memory_estimate.hpp"
#include "seiche/output_files.hpp"
#include "seiche/particle_store.hpp"
#include "seiche/runner.hpp"
#include "seiche/scene.hpp"
#include "seiche/scene_loader.hpp"
#include "seiche/simulation.hpp"
#include "seiche/stability.hpp"
#include "seiche/thread_count.hpp"
