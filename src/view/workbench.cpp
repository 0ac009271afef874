// SPDX-License-Identifier: Apache-2.0
// The interactive workbench: one GLFW window with an OpenGL 3.3 core context, a Dear ImGui
// panel on the left and the views on the right. Input from GLFW and from event scripts goes
// through one queue (so a recorded session replays through the same path), and the frame loop
// only reads what the worker threads hand over (SegmentSession), never waits for them.
#include "ido/geometry/aabb.h"
#include "ido/view/workbench.h"

#include "gl_draw.h"  // first: defines GL_GLEXT_PROTOTYPES before any GL header

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <imgui.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cfloat>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "ido/core/atomic_file.h"
#include "ido/core/error.h"
#include "ido/drill/udp_bridge.h"
#include "ido/geometry/mesh_checks.h"
#include "ido/geometry/tet_quality.h"
#include "ido/geometry/vertex_clustering.h"
#include "ido/io/mesh_io.h"
#include "ido/meshing/tetrahedralize.h"
#include "ido/io/scene.h"
#include "ido/io/volume_io.h"
#include "ido/segment/balloon.h"
#include "ido/view/deform_session.h"
#include "ido/view/drill_session.h"
#include "ido/view/event_script.h"
#include "ido/view/orbit_camera.h"
#include "ido/view/segment_session.h"
#include "ido/view/slice_view.h"
#include "ido/view/tet_section.h"
#include "ido/viz/renderer.h"

namespace ido::view {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kPanelWidthPx = 340.0;
const Vec3 kBalloonColour(0.85, 0.55, 0.4);  // as `ido segment --snapshots`
const Vec3 kSeedColour(0.1, 1.0, 0.2);
const Vec3 kStopColour(0.2, 0.75, 1.0);
const Vec3 kContourColour(1.0, 0.15, 0.1);
const Vec3 kCrosshairColour(0.9, 0.8, 0.2);
const Vec3 kSectionColour(1.0, 0.85, 0.3);
const Vec3 kSectionEdgeColour(0.35, 0.2, 0.05);
const Vec3 kMaterialColour(0.9, 0.85, 0.7);  // as `ido drill --snapshots`
const Vec3 kToolColour(0.6, 0.65, 0.75);
const Vec3 kForceColour(1.0, 0.2, 0.9);
const Vec3 kRoiColour(1.0, 0.55, 0.0);
const std::array<Vec3, 4> kObjectColours = {Vec3(0.8, 0.8, 0.85), Vec3(0.55, 0.75, 0.95), Vec3(0.7, 0.9, 0.6),
                                            Vec3(0.95, 0.85, 0.5)};
// The Deform workspace's body markers (its bodies are coloured by a field): not in viridis.
const std::array<Vec3, 4> kBodyMarkers = {Vec3(1.0, 0.3, 0.3), Vec3(0.2, 0.9, 1.0), Vec3(1.0, 0.6, 0.1), Vec3(1.0, 0.4, 1.0)};
const std::array<const char*, 3> kAxisNames = {"sagittal", "coronal", "axial"};
const std::array<const char*, 3> kIndexNames = {"i", "j", "k"};

// ---- key names (scripts) <-> GLFW key codes ------------------------------------------------

int key_code(std::string_view name) {
  static const std::map<std::string_view, int> named = {
      {"space", GLFW_KEY_SPACE},     {"enter", GLFW_KEY_ENTER},       {"escape", GLFW_KEY_ESCAPE},
      {"tab", GLFW_KEY_TAB},         {"backspace", GLFW_KEY_BACKSPACE}, {"delete", GLFW_KEY_DELETE},
      {"insert", GLFW_KEY_INSERT},   {"left", GLFW_KEY_LEFT},         {"right", GLFW_KEY_RIGHT},
      {"up", GLFW_KEY_UP},           {"down", GLFW_KEY_DOWN},         {"page_up", GLFW_KEY_PAGE_UP},
      {"page_down", GLFW_KEY_PAGE_DOWN}, {"home", GLFW_KEY_HOME},     {"end", GLFW_KEY_END},
      {"keypad_enter", GLFW_KEY_KP_ENTER}, {"minus", GLFW_KEY_MINUS}, {"equal", GLFW_KEY_EQUAL},
  };
  if (name.size() == 1 && name[0] >= 'a' && name[0] <= 'z') return GLFW_KEY_A + (name[0] - 'a');
  if (name.size() == 1 && name[0] >= '0' && name[0] <= '9') return GLFW_KEY_0 + (name[0] - '0');
  if (name.size() >= 2 && name.size() <= 3 && name[0] == 'f') {
    int n = 0;
    for (char c : name.substr(1)) n = (c >= '0' && c <= '9') ? 10 * n + (c - '0') : -100;
    if (n >= 1 && n <= 12) return GLFW_KEY_F1 + n - 1;
  }
  const auto it = named.find(name);
  return it == named.end() ? -1 : it->second;
}

std::string key_name(int code) {
  if (code >= GLFW_KEY_A && code <= GLFW_KEY_Z) return std::string(1, char('a' + (code - GLFW_KEY_A)));
  if (code >= GLFW_KEY_0 && code <= GLFW_KEY_9) return std::string(1, char('0' + (code - GLFW_KEY_0)));
  if (code >= GLFW_KEY_F1 && code <= GLFW_KEY_F12) return fmt::format("f{}", code - GLFW_KEY_F1 + 1);
  for (const char* n : {"space", "enter", "escape", "tab", "backspace", "delete", "insert", "left", "right", "up",
                        "down", "page_up", "page_down", "home", "end", "keypad_enter", "minus", "equal"})
    if (key_code(n) == code) return n;
  return {};
}

gl::Mat4f to_float(const Mat4& m) { return m.cast<float>(); }

/// A grey-level window (width, centre) spanning the 1st to the 99th percentile of a sample.
std::array<double, 2> auto_window(const image::Volume<float>& ct) {
  std::vector<float> sample;
  const std::size_t n = ct.voxel_count(), stride = std::max<std::size_t>(1, n / 20000);
  const float* data = &ct(0, 0, 0);
  for (std::size_t i = 0; i < n; i += stride) sample.push_back(data[i]);
  std::sort(sample.begin(), sample.end());
  const double lo = sample[sample.size() / 100], hi = sample[sample.size() - 1 - sample.size() / 100];
  const double width = std::max(hi - lo, 1e-6);
  return {width, 0.5 * (lo + hi)};
}

struct SceneObject {
  std::string name;
  geometry::TriangleMesh mesh;  ///< drawn; for a tetrahedral mesh its boundary
  Vec3 colour;
  bool visible = true;
  std::unique_ptr<gl::MeshBuffer> gpu;
  std::shared_ptr<const geometry::TetMesh> tets = nullptr;  ///< a tetrahedral mesh file's cells (shared with mesh jobs)
  bool cull_back = false;  ///< one closed surface, outward: its back faces are not drawn
  /// A coarser copy drawn instead while the camera moves (surfaces above kCoarseAbove
  /// triangles only; null otherwise).
  std::unique_ptr<gl::MeshBuffer> coarse = nullptr;
};

/// Level of detail while the camera moves ("LOD while interacting", as ParaView and VTK do):
/// a surface of more than kCoarseAbove triangles is also uploaded decimated to at most
/// kCoarseTriangles (geometry::cluster_vertices_to), drawn while a camera drag is held or the
/// camera changed in that frame; the full surface is drawn once it stops. With llvmpipe on two
/// cores the cost of a moving view is its triangles (bench/results/view.md).
constexpr std::size_t kCoarseAbove = 60'000, kCoarseTriangles = 30'000;

/// SCHED_FIFO priority the window's drilling sessions ask for their collision/erosion thread:
/// below the haptic thread's (drill::SimulatorOptions::haptic_realtime_priority, 80).
constexpr int kCollisionPriority = 60;

/// Uploads @p o's surface, and its coarse copy when it is large.
void upload_object(SceneObject& o) {
  o.gpu = std::make_unique<gl::MeshBuffer>();
  o.gpu->upload(o.mesh, o.colour);
  o.coarse.reset();
  if (o.mesh.triangle_count() > kCoarseAbove) {
    o.coarse = std::make_unique<gl::MeshBuffer>();
    o.coarse->upload(geometry::cluster_vertices_to(o.mesh, kCoarseTriangles), o.colour);
  }
}

/// True for one closed, oriented surface whose triangles are counter-clockwise seen from
/// outside: its back faces are hidden behind its front, so they need not be drawn.
bool closed_outward(const geometry::TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return false;
  try {
    const geometry::MeshCheckReport r = geometry::check_mesh(mesh);
    return r.closed && r.oriented && r.vertex_manifold && r.components == 1 && r.signed_volume_mm3 > 0;
  } catch (const std::exception&) {
    return false;
  }
}

/// Work on its own thread whose end the frame loop polls (saving files, tetrahedralising).
struct Job {
  std::thread thread;
  std::atomic<int> state{0};  // 0 running, 1 done, 2 failed
  std::string message;        // written before state is released
};

/// A tetrahedral mesh for the Mesh workspace and what is measured on it.
struct MeshResult {
  std::string source;
  geometry::TetMesh mesh;
  geometry::TetMeshReport report;
  std::vector<std::size_t> histogram;  // dihedral angles, 36 bins of 5°
  geometry::TriangleMesh boundary;
};

/// What a click on a slice placed: a seed, or a stop point (the balloon's front does not pass it).
enum class MarkKind { Seed, Stop };
struct Mark {
  MarkKind kind = MarkKind::Seed;
  Index3 voxel = {0, 0, 0};
};

/// What the Deform workspace colours its bodies by.
enum class DeformField { Displacement, VonMises, Strain };
constexpr std::array<const char*, 3> kDeformFieldNames = {"displacement", "von Mises stress", "equivalent strain"};
constexpr std::array<const char*, 3> kDeformFieldUnits = {"mm", "kPa", "1 (Green)"};

/// A body's boundary: faces (global particle indices) and the tetrahedron (local index) of each.
struct BodySurface {
  std::vector<Tri> faces;
  std::vector<std::int32_t> face_tet;
};

BodySurface body_surface(const io::SceneBody& body) {
  std::map<std::array<std::int32_t, 3>, std::pair<int, std::pair<Tri, std::int32_t>>> faces;
  const geometry::TetMesh& mesh = body.rest_mesh;
  for (std::size_t ti = 0; ti < mesh.tets.size(); ++ti) {
    const Tet& t = mesh.tets[ti];
    for (int f = 0; f < 4; ++f) {
      Tri tri = {t[std::size_t((f + 1) % 4)], t[std::size_t((f + 2) % 4)], t[std::size_t((f + 3) % 4)]};
      const Vec3& a = mesh.vertices[std::size_t(tri[0])];
      const Vec3 n = (mesh.vertices[std::size_t(tri[1])] - a).cross(mesh.vertices[std::size_t(tri[2])] - a);
      if (n.dot(mesh.vertices[std::size_t(t[std::size_t(f)])] - a) > 0) std::swap(tri[1], tri[2]);  // outward
      std::array<std::int32_t, 3> key = tri;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, 0, std::pair{tri, std::int32_t(ti)});
      ++it->second.first;
    }
  }
  BodySurface out;
  for (const auto& [key, v] : faces)
    if (v.first == 1) {
      Tri g = v.second.first;
      for (auto& i : g) i += body.first_particle;
      out.faces.push_back(g);
      out.face_tet.push_back(v.second.second);
    }
  return out;
}

class Workbench {
 public:
  explicit Workbench(const WorkbenchOptions& options);
  ~Workbench();
  Workbench(const Workbench&) = delete;
  Workbench& operator=(const Workbench&) = delete;
  void run();
  /// What run() measured (moved out).
  [[nodiscard]] WorkbenchStats take_stats() { return std::move(m_stats); }

 private:
  // set-up
  void load_files();
  void open_window();
  void open_offscreen();
  void init_gl();
  /// --snapshot: waits for the workers, draws one frame off-screen and writes it.
  void snapshot();
  /// The views' size in points and the framebuffer's in pixels.
  void surface_size(int& win_w, int& win_h, int& fb_w, int& fb_h) const;
  // input
  void on_input(InputEvent e);
  bool feed_script();
  void apply_input();
  void view_mouse_down(const InputEvent& e);
  void view_mouse_up(const InputEvent& e);
  void view_mouse_move(const InputEvent& e);
  void view_scroll(const InputEvent& e);
  void shortcut(const InputEvent& e);
  // actions
  void place_mark(MarkKind kind, const Index3& voxel);
  [[nodiscard]] segment::BalloonChoices balloon_choices() const;
  [[nodiscard]] geometry::Aabb roi_of_drag() const;
  void set_roi(std::optional<geometry::Aabb> roi_mm);
  void roi_panel();
  void restart_balloon();
  void undo_mark();
  [[nodiscard]] std::vector<Vec3> marks_mm(MarkKind kind) const;
  void toggle_pause();
  void step_once();
  void accept();
  void save();
  void start_save(std::function<std::string()> work);
  void tetrahedralise();
  [[nodiscard]] viz::ClipPlane clip_plane() const;
  void rebuild_section();
  void drill_panel();
  void deform_panel();
  void energy_plots(const DeformState& st);
  void parameter_panel(const DeformState& st);
  void update_deform();
  void grab(double x_px, double y_px);
  void colour_bar();
  /// A legend box (a colour swatch and a name per entry) at the 3-D view's top right; nothing
  /// for fewer than two entries.
  void legend(const std::vector<std::pair<std::string, Vec3>>& entries);
  /// The Deform workspace's bodies named and numbered, the numbers drawn on the bodies.
  void body_legend();
  void write_deform_log();
  void toggle_drilling();
  void start_drilling(std::unique_ptr<drill::HapticDevice> source, double max_duration_s, const std::string& what);
  void replay_path();
  void connect_device();
  void move_tool(const Vec3& position_mm);
  void draw_tool(const drill::ToolPose& pose);
  void turn_tool(double tilt_deg, double azimuth_deg);
  [[nodiscard]] Eigen::Quaterniond tool_orientation() const;
  void drill_ended();
  [[nodiscard]] std::shared_ptr<const geometry::TetMesh> drill_material() const;
  [[nodiscard]] bool drilling() { return m_drill && m_drill->started() && !m_drill->ended(); }
  void set_slice(int axis, std::int64_t index);
  // frame
  void layout(double width, double height);
  void update_from_workers();
  void panel();
  void overlays();
  void mesh_panel();
  void draw(int fb_width, int fb_height);
  void draw_3d(const PixelRect& rect, double fb_scale, int fb_height);
  /// Draws the 3-D view's content into the bound framebuffer's viewport (aspect of @p rect).
  void render_3d(const PixelRect& rect);
  /// Scene, Segment and Mesh: the 3-D view is drawn into m_view_cache only when what it shows
  /// changed (camera, size, buffers, visibility, window/level, clip plane), else copied from it.
  void draw_3d_cached(const PixelRect& rect, double fb_scale, int fb_height);
  [[nodiscard]] std::vector<double> view_key(int w_px, int h_px) const;
  void draw_slice_view(int axis, double fb_scale, int fb_height);
  void rebuild_contours();
  void upload_slice(int axis);
  void frame_camera();
  [[nodiscard]] bool condition_holds(const InputEvent& wait);
  [[nodiscard]] bool save_running() const { return m_save && m_save->state.load() == 0; }
  [[nodiscard]] bool mesh_running() const { return m_mesh_job && m_mesh_job->state.load() == 0; }
  void say(const std::string& text);

  WorkbenchOptions m_options;
  std::optional<EventScript> m_script;
  std::size_t m_next_event = 0;
  std::int64_t m_script_frame = 0;
  std::optional<Clock::time_point> m_wait_start;
  std::optional<std::int64_t> m_wait_base_steps;  // "deform_steps": the step count when the wait began
  std::vector<std::string> m_pending_screenshots;
  std::vector<InputEvent> m_recorded;
  std::vector<InputEvent> m_queue;
  std::int64_t m_frame = 0;

  // scene
  std::shared_ptr<const image::Volume<float>> m_ct;  // shared with the SegmentSession's workers
  std::string m_ct_name;
  std::vector<SceneObject> m_objects;
  geometry::Aabb m_bounds{Vec3::Zero(), Vec3::Ones()};

  // window and GL
  GLFWwindow* m_window = nullptr;
  // --snapshot: an off-screen context (EGL, surfaceless) drawing into a framebuffer object
  EGLDisplay m_egl_display = EGL_NO_DISPLAY;
  EGLContext m_egl_context = EGL_NO_CONTEXT;
  GLuint m_fbo = 0, m_fbo_colour = 0, m_fbo_depth = 0;
  double m_panel_px = kPanelWidthPx;  // 0 in a snapshot: the picture is the views
  // The 3-D view's last picture (draw_3d_cached) and what it showed.
  GLuint m_cache_fbo = 0, m_cache_colour = 0, m_cache_depth = 0;
  int m_cache_w = 0, m_cache_h = 0;
  std::vector<double> m_cache_key;
  std::int64_t m_cache_draws = 0;  // times the cached view was drawn (not copied)
  bool m_imgui = false;
  std::unique_ptr<gl::Painter> m_painter;
  std::unique_ptr<gl::MeshBuffer> m_balloon_gpu;
  std::array<std::unique_ptr<gl::SliceQuad>, 3> m_slice_2d, m_slice_3d;
  std::array<std::unique_ptr<gl::LineBuffer>, 3> m_contours, m_marks;
  std::unique_ptr<gl::LineBuffer> m_marks_3d;

  // views
  Workspace m_workspace = Workspace::Scene;
  std::optional<Workspace> m_select_tab;
  PixelRect m_view_area, m_rect_3d;
  std::array<std::optional<SliceView>, 3> m_slice_views;
  OrbitCamera m_camera;
  std::array<std::int64_t, 3> m_slice = {0, 0, 0};
  double m_window_width = 1, m_level = 0;
  enum class Drag { None, Rotate, Pan, WindowLevel, Clip, Tool, Grab, Roi } m_drag = Drag::None;
  double m_mouse_x = 0, m_mouse_y = 0;
  bool m_camera_moving = false;   // this frame: large surfaces drawn coarse (draw())
  std::optional<Mat4> m_last_view;  // the camera's view matrix in the last frame drawn
  bool m_capture_mouse = false, m_capture_keyboard = false;  // ImGui's wish in the last frame

  // segmentation
  std::unique_ptr<SegmentSession> m_session;
  segment::Organ m_organ = segment::Organ::Generic;
  std::vector<Mark> m_placed;  // seeds and stop points in the order placed (ctrl+z removes the last)
  bool m_click_stops = false;  // a plain click places a stop point (shift+click always does)
  std::optional<geometry::Aabb> m_roi_mm;  // the region of interest (world mm)
  std::optional<double> m_max_radius_mm;   // the bound on the organ's local radius (mm)
  bool m_drags_draw_roi = false;           // a plain drag on a slice draws the region (ctrl+drag always does)
  int m_roi_axis = -1;                     // the slice a region is being drawn on
  std::array<std::int64_t, 2> m_roi_from{}, m_roi_to{};  // its first and current voxel (in-plane indices)
  std::shared_ptr<const SegmentState> m_state;
  bool m_contours_dirty = true;
  int m_accepted = 0;
  std::unique_ptr<Job> m_save;
  std::string m_message;

  // tetrahedral meshing
  int m_mesh_source = -1;  // index into m_objects
  double m_tet_edge_mm = 0.0;
  std::unique_ptr<Job> m_mesh_job;
  std::shared_ptr<MeshResult> m_mesh_pending;  // written by m_mesh_job until it is done
  std::shared_ptr<const MeshResult> m_mesh;
  std::unique_ptr<gl::MeshBuffer> m_tet_gpu, m_section_gpu;
  std::unique_ptr<gl::LineBuffer> m_section_lines;
  int m_clip_axis = 1;
  bool m_clip_flip = false;
  double m_clip_offset_mm = 0.0;
  bool m_clip_drag = false;
  bool m_section_dirty = false;
  Vec3 m_section_normal = Vec3::Zero();
  std::size_t m_cut_tets = 0;

  // drilling
  std::unique_ptr<DrillSession> m_drill;
  bool m_drill_reported = false;
  Vec3 m_tool_mm = Vec3::Zero();
  double m_tool_tilt_deg = 0.0, m_tool_azimuth_deg = 0.0;  // the tool's axis (its shaft): see tool_orientation()
  Eigen::Quaterniond m_tool_shown = Eigen::Quaterniond::Identity();  // drawn, when a path or device moves the tool
  std::shared_ptr<const DrillSnapshot> m_drill_surface;
  std::unique_ptr<gl::MeshBuffer> m_drill_gpu, m_tool_gpu;
  std::unique_ptr<gl::LineBuffer> m_force_lines;
  Vec3 m_force_shown_n = Vec3::Constant(NAN), m_force_at_mm = Vec3::Constant(NAN);  // what m_force_lines holds
  DrillFigures m_figures;
  std::string m_drill_summary;
  std::string m_drill_source = "mouse";  // what moved the tool of the last session: mouse, path:FILE, udp:PORT
  std::array<char, 1024> m_replay_path{};  // the panel's path CSV to replay

  // deformation
  std::unique_ptr<DeformSession> m_deform;
  std::vector<BodySurface> m_body_surfaces;
  std::vector<std::string> m_body_names;
  std::vector<Vec3> m_rest_positions;
  std::shared_ptr<const DeformState> m_deform_state;
  std::unique_ptr<gl::MeshBuffer> m_deform_gpu;
  std::unique_ptr<gl::LineBuffer> m_grab_lines;
  DeformField m_field = DeformField::Displacement;
  bool m_field_dirty = true;
  std::array<double, 2> m_field_range = {0.0, 1.0};
  GrabSpring m_grab;
  double m_grab_stiffness_n_per_mm = 0.1;
  std::int32_t m_logged_particle = -1;
  nlohmann::json m_deform_log = nlohmann::json::array();
  std::vector<double> m_parameter_edit;  // the panel's values of the scene's parameters
  std::vector<double> m_parameter_seen;  // the values in use when they were last taken over
  std::string m_parameter_error_seen;
  int m_focus_parameter = -1;  // the parameter field to give the keyboard to (e)

  // frame timing
  std::vector<double> m_frame_ms;
  Clock::time_point m_last_frame = Clock::now();
  WorkbenchStats m_stats;
};

Workbench::Workbench(const WorkbenchOptions& options)
    : m_options(options), m_organ(options.organ), m_roi_mm(options.roi_mm), m_max_radius_mm(options.max_radius_mm),
      m_tet_edge_mm(options.tet_edge_mm) {
  check_segment_outputs(m_options.segment_outputs);
  if (!m_options.tet_output.empty() && !io::is_tet_mesh_path(m_options.tet_output))
    throw InvalidInput(fmt::format("--tet-output {}: must be a .vtu, .msh or .node file", m_options.tet_output.string()));
  if (!(m_options.burr_radius_mm > 0) || !std::isfinite(m_options.burr_radius_mm))
    throw InvalidInput(fmt::format("--burr-radius {}: must be a positive length (mm)", m_options.burr_radius_mm));
  if (!(m_options.shaft_radius_mm >= 0) || !(m_options.shaft_radius_mm < m_options.burr_radius_mm))
    throw InvalidInput(fmt::format("--shaft-radius {}: must be 0 (no shaft) or less than the burr radius ({} mm)",
                                   m_options.shaft_radius_mm, m_options.burr_radius_mm));
  if (!(m_options.drill_max_s > 0) || m_options.drill_max_s > drill::kMaxScriptDuration_s)
    throw InvalidInput(fmt::format("--drill-max {}: a session lasts 0..{} s", m_options.drill_max_s, drill::kMaxScriptDuration_s));
  if (!(m_tet_edge_mm >= 0) || !std::isfinite(m_tet_edge_mm))
    throw InvalidInput(fmt::format("--tet-edge {}: the lattice spacing must be 0 (automatic) or a positive length (mm)", m_tet_edge_mm));
  if (!m_options.script.empty()) {
    m_script = EventScript::load(m_options.script);
    m_options.width_px = m_script->window_width_px;
    m_options.height_px = m_script->window_height_px;
    for (const InputEvent& e : m_script->events)
      if (e.kind == EventKind::Screenshot && m_options.screenshots.empty())
        throw InvalidInput(fmt::format("{}: the script takes screenshots: give --screenshots DIR", m_options.script.string()));
  }
  if (!m_options.screenshots.empty()) {
    std::error_code ec;
    fs::create_directories(m_options.screenshots, ec);
    if (!fs::is_directory(m_options.screenshots))
      throw InvalidInput(fmt::format("--screenshots {}: not a folder and cannot be created", m_options.screenshots.string()));
  }
  if (m_options.width_px < 64 || m_options.height_px < 64 || m_options.width_px > 8192 || m_options.height_px > 8192)
    throw InvalidInput("the window size must be 64..8192 pixels each way");
  load_files();
  for (const auto& [voxels, option] :
       {std::pair{&m_options.seed_voxels, "--seed-voxel"}, {&m_options.stop_voxels, "--stop-voxel"}}) {
    if (!m_ct && !voxels->empty()) throw InvalidInput(fmt::format("{} needs a volume to segment", option));
    for (const Index3& v : *voxels)
      if (!m_ct->contains(v[0], v[1], v[2]))
        throw InvalidInput(fmt::format("{} {},{},{}: outside the {}x{}x{} volume", option, v[0], v[1], v[2],
                                       m_ct->size(0), m_ct->size(1), m_ct->size(2)));
  }
  if (m_roi_mm || m_max_radius_mm) {
    if (!m_ct) throw InvalidInput(m_roi_mm ? "--roi needs a volume to segment" : "--max-radius needs a volume to segment");
    // Refused as the library refuses them, naming the flag.
    (void)segment::balloon_options(balloon_choices(), [](std::string_view field) {
      return std::string(field == "roi" ? "--roi" : field == "max_radius_mm" ? "--max-radius" : field);
    });
  }
  if (m_options.drill_udp_port < 0 || m_options.drill_udp_port > 65535)
    throw InvalidInput(fmt::format("--drill-udp {}: a UDP port is 0..65535 (0: any free port)", m_options.drill_udp_port));
  if (!m_options.drill_replay.empty()) {
    (void)drill::ScriptedTrajectory::load_csv(m_options.drill_replay, 1);  // a bad path is refused now, by name
    const std::string p = m_options.drill_replay.string();
    std::copy_n(p.begin(), std::min(p.size(), m_replay_path.size() - 1), m_replay_path.begin());
  }
  if (m_options.snapshot.empty())
    open_window();
  else
    open_offscreen();
  init_gl();
}

Workbench::~Workbench() {
  m_session.reset();  // joins the balloon's workers
  if (m_save && m_save->thread.joinable()) m_save->thread.join();
  if (m_mesh_job && m_mesh_job->thread.joinable()) m_mesh_job->thread.join();
  m_drill.reset();  // stops and joins the session's threads
  m_deform.reset();
  m_deform_gpu.reset();
  m_grab_lines.reset();
  m_drill_gpu.reset();
  m_tool_gpu.reset();
  m_force_lines.reset();
  m_tet_gpu.reset();
  m_section_gpu.reset();
  m_section_lines.reset();
  // GL objects go while the context is still current.
  m_painter.reset();
  m_balloon_gpu.reset();
  for (auto& q : m_slice_2d) q.reset();
  for (auto& q : m_slice_3d) q.reset();
  for (auto& l : m_contours) l.reset();
  for (auto& l : m_marks) l.reset();
  m_marks_3d.reset();
  for (auto& o : m_objects) o.gpu.reset();
  if (m_imgui) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui::DestroyContext();
  }
  if (m_cache_fbo) {
    glDeleteFramebuffers(1, &m_cache_fbo);
    glDeleteRenderbuffers(1, &m_cache_colour);
    glDeleteRenderbuffers(1, &m_cache_depth);
  }
  if (m_fbo) {
    glDeleteFramebuffers(1, &m_fbo);
    glDeleteRenderbuffers(1, &m_fbo_colour);
    glDeleteRenderbuffers(1, &m_fbo_depth);
  }
  if (m_egl_display != EGL_NO_DISPLAY) {
    eglMakeCurrent(m_egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    if (m_egl_context != EGL_NO_CONTEXT) eglDestroyContext(m_egl_display, m_egl_context);
    eglTerminate(m_egl_display);
  }
  if (m_window) glfwDestroyWindow(m_window);
  if (m_options.snapshot.empty()) glfwTerminate();
}

void Workbench::say(const std::string& text) {
  m_message = text;
  if (!m_options.quiet) std::printf("%s\n", text.c_str());
}

void Workbench::load_files() {
  for (const fs::path& f : m_options.files) {
    const std::string ext = f.extension().string();
    if (io::looks_like_volume(f)) {
      if (m_ct) throw InvalidInput(fmt::format("{}: one volume at a time (already {})", f.string(), m_ct_name));
      m_ct = std::make_shared<const image::Volume<float>>(io::read_volume(f));
      m_ct_name = f.string();
    } else if (ext == ".json") {
      io::Scene scene = io::load_scene(f);
      for (const io::SceneBody& b : scene.bodies) {
        geometry::TetMesh posed = b.rest_mesh;
        for (std::size_t i = 0; i < posed.vertices.size(); ++i)
          posed.vertices[i] = scene.world.particles().positions()[std::size_t(b.first_particle) + i];
        m_objects.push_back({f.filename().string() + ": " + b.name, geometry::tet_boundary(posed),
                             kObjectColours[m_objects.size() % kObjectColours.size()], true, nullptr});
      }
      if (!m_deform && !scene.bodies.empty()) {  // the first scene is the Deform workspace's
        m_rest_positions = scene.world.particles().positions();
        for (const io::SceneBody& b : scene.bodies) {
          m_body_surfaces.push_back(body_surface(b));
          m_body_names.push_back(b.name);
        }
        m_deform = std::make_unique<DeformSession>(f);  // keeps the file's text: its parameters can change
        m_deform_state = m_deform->latest();
        for (const SceneParameter& p : m_deform->parameters()) m_parameter_edit.push_back(p.value);
        m_parameter_seen = m_parameter_edit;
      }
    } else if (io::is_triangle_mesh_path(f)) {
      m_objects.push_back({f.filename().string(), io::read_triangle_mesh(f),
                           kObjectColours[m_objects.size() % kObjectColours.size()], true, nullptr});
    } else if (io::is_tet_mesh_path(f)) {
      auto tets = std::make_shared<const geometry::TetMesh>(io::read_tet_mesh(f));
      m_objects.push_back({f.filename().string(), geometry::tet_boundary(*tets),
                           kObjectColours[m_objects.size() % kObjectColours.size()], true, nullptr, tets});
    } else {
      throw InvalidInput(fmt::format("{}: not a volume, surface, tetrahedral mesh or scene (.json) file", f.string()));
    }
  }
  geometry::Aabb box;
  if (m_ct) {
    for (int c = 0; c < 8; ++c) {
      const Vec3 idx((c & 1) ? double(m_ct->size(0)) - 0.5 : -0.5, (c & 2) ? double(m_ct->size(1)) - 0.5 : -0.5,
                     (c & 4) ? double(m_ct->size(2)) - 0.5 : -0.5);
      box.extend(m_ct->index_to_world(idx));
    }
  }
  for (const auto& o : m_objects)
    for (const Vec3& p : o.mesh.vertices) box.extend(p);
  if (box.min.allFinite() && box.max.allFinite()) m_bounds = box;
  for (auto& o : m_objects) o.cull_back = closed_outward(o.mesh);
  if (!m_objects.empty()) m_mesh_source = 0;
  m_clip_offset_mm = 0.5 * (m_bounds.min[m_clip_axis] + m_bounds.max[m_clip_axis]);
  if (m_ct) {
    m_workspace = Workspace::Segment;
    for (int a = 0; a < 3; ++a) m_slice[std::size_t(a)] = m_ct->size(a) / 2;
    const auto [w, l] = auto_window(*m_ct);
    m_window_width = w;
    m_level = l;
    m_session = std::make_unique<SegmentSession>(m_ct);
    m_state = m_session->latest();
  }
}

void Workbench::open_window() {
  glfwSetErrorCallback([](int, const char*) {});
  if (!glfwInit())
    throw Error("ido view needs a display: none could be opened (set DISPLAY, or run it under xvfb-run)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  glfwWindowHint(GLFW_RESIZABLE, m_script ? GLFW_FALSE : GLFW_TRUE);
  m_window = glfwCreateWindow(m_options.width_px, m_options.height_px, "ido view", nullptr, nullptr);
  if (!m_window) throw Error("ido view: no OpenGL 3.3 core context could be created on this display");
  glfwMakeContextCurrent(m_window);
  glfwSwapInterval(m_script ? 0 : 1);
  glfwSetWindowUserPointer(m_window, this);
  // Live input goes through the same queue as a script's events (and into the recording).
  glfwSetCursorPosCallback(m_window, [](GLFWwindow* w, double x, double y) {
    InputEvent e;
    e.kind = EventKind::MouseMove;
    e.x_px = x;
    e.y_px = y;
    static_cast<Workbench*>(glfwGetWindowUserPointer(w))->on_input(e);
  });
  glfwSetMouseButtonCallback(m_window, [](GLFWwindow* w, int button, int action, int mods) {
    if (button > 2) return;
    InputEvent e;
    e.kind = action == GLFW_PRESS ? EventKind::MouseDown : EventKind::MouseUp;
    e.button = button == GLFW_MOUSE_BUTTON_LEFT ? 0 : button == GLFW_MOUSE_BUTTON_RIGHT ? 1 : 2;
    e.ctrl = (mods & GLFW_MOD_CONTROL) != 0;
    e.shift = (mods & GLFW_MOD_SHIFT) != 0;
    e.alt = (mods & GLFW_MOD_ALT) != 0;
    glfwGetCursorPos(w, &e.x_px, &e.y_px);
    static_cast<Workbench*>(glfwGetWindowUserPointer(w))->on_input(e);
  });
  glfwSetScrollCallback(m_window, [](GLFWwindow* w, double, double dy) {
    InputEvent e;
    e.kind = EventKind::Scroll;
    e.scroll_y = dy;
    glfwGetCursorPos(w, &e.x_px, &e.y_px);
    static_cast<Workbench*>(glfwGetWindowUserPointer(w))->on_input(e);
  });
  glfwSetKeyCallback(m_window, [](GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_REPEAT) return;
    InputEvent e;
    e.kind = action == GLFW_PRESS ? EventKind::KeyDown : EventKind::KeyUp;
    e.key = key_name(key);
    if (e.key.empty()) return;
    e.ctrl = (mods & GLFW_MOD_CONTROL) != 0;
    e.shift = (mods & GLFW_MOD_SHIFT) != 0;
    e.alt = (mods & GLFW_MOD_ALT) != 0;
    static_cast<Workbench*>(glfwGetWindowUserPointer(w))->on_input(e);
  });
  glfwSetCharCallback(m_window, [](GLFWwindow* w, unsigned int c) {
    InputEvent e;
    e.kind = EventKind::Char;
    e.codepoint = c;
    static_cast<Workbench*>(glfwGetWindowUserPointer(w))->on_input(e);
  });
}

void Workbench::open_offscreen() {
  // Mesa's surfaceless platform: an OpenGL 3.3 core context with no display and no window,
  // drawing into a framebuffer object. libGL's functions dispatch to it (GLVND).
  m_panel_px = 0.0;
  const auto fail = [](const char* what) {
    return Error(fmt::format("--snapshot: no off-screen OpenGL 3.3 context ({}; EGL error 0x{:x})", what, eglGetError()));
  };
  const auto get_platform_display =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!get_platform_display) throw fail("EGL has no eglGetPlatformDisplayEXT");
  m_egl_display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  EGLint major = 0, minor = 0;
  if (m_egl_display == EGL_NO_DISPLAY || !eglInitialize(m_egl_display, &major, &minor)) {
    m_egl_display = EGL_NO_DISPLAY;
    throw fail("Mesa's surfaceless platform");
  }
  if (!eglBindAPI(EGL_OPENGL_API)) throw fail("desktop OpenGL");
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  m_egl_context = eglCreateContext(m_egl_display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
  if (m_egl_context == EGL_NO_CONTEXT) throw fail("context");
  if (!eglMakeCurrent(m_egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, m_egl_context)) throw fail("make current");
  glGenFramebuffers(1, &m_fbo);
  glGenRenderbuffers(1, &m_fbo_colour);
  glGenRenderbuffers(1, &m_fbo_depth);
  glBindFramebuffer(GL_FRAMEBUFFER, m_fbo);
  glBindRenderbuffer(GL_RENDERBUFFER, m_fbo_colour);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, m_options.width_px, m_options.height_px);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m_fbo_colour);
  glBindRenderbuffer(GL_RENDERBUFFER, m_fbo_depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, m_options.width_px, m_options.height_px);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m_fbo_depth);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) throw fail("framebuffer");
}

void Workbench::surface_size(int& win_w, int& win_h, int& fb_w, int& fb_h) const {
  if (!m_window) {
    win_w = fb_w = m_options.width_px;
    win_h = fb_h = m_options.height_px;
    return;
  }
  glfwGetWindowSize(m_window, &win_w, &win_h);
  glfwGetFramebufferSize(m_window, &fb_w, &fb_h);
}

void Workbench::init_gl() {
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  m_imgui = true;
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;  // the layout is fixed: nothing to remember between sessions
  io.BackendPlatformName = "ido_view";
  io.KeyMap[ImGuiKey_Tab] = GLFW_KEY_TAB;
  io.KeyMap[ImGuiKey_LeftArrow] = GLFW_KEY_LEFT;
  io.KeyMap[ImGuiKey_RightArrow] = GLFW_KEY_RIGHT;
  io.KeyMap[ImGuiKey_UpArrow] = GLFW_KEY_UP;
  io.KeyMap[ImGuiKey_DownArrow] = GLFW_KEY_DOWN;
  io.KeyMap[ImGuiKey_PageUp] = GLFW_KEY_PAGE_UP;
  io.KeyMap[ImGuiKey_PageDown] = GLFW_KEY_PAGE_DOWN;
  io.KeyMap[ImGuiKey_Home] = GLFW_KEY_HOME;
  io.KeyMap[ImGuiKey_End] = GLFW_KEY_END;
  io.KeyMap[ImGuiKey_Insert] = GLFW_KEY_INSERT;
  io.KeyMap[ImGuiKey_Delete] = GLFW_KEY_DELETE;
  io.KeyMap[ImGuiKey_Backspace] = GLFW_KEY_BACKSPACE;
  io.KeyMap[ImGuiKey_Space] = GLFW_KEY_SPACE;
  io.KeyMap[ImGuiKey_Enter] = GLFW_KEY_ENTER;
  io.KeyMap[ImGuiKey_Escape] = GLFW_KEY_ESCAPE;
  io.KeyMap[ImGuiKey_KeyPadEnter] = GLFW_KEY_KP_ENTER;
  io.KeyMap[ImGuiKey_A] = GLFW_KEY_A;
  io.KeyMap[ImGuiKey_C] = GLFW_KEY_C;
  io.KeyMap[ImGuiKey_V] = GLFW_KEY_V;
  io.KeyMap[ImGuiKey_X] = GLFW_KEY_X;
  io.KeyMap[ImGuiKey_Y] = GLFW_KEY_Y;
  io.KeyMap[ImGuiKey_Z] = GLFW_KEY_Z;
  ImGui::StyleColorsDark();
  if (!ImGui_ImplOpenGL3_Init("#version 330 core")) throw Error("ido view: Dear ImGui's OpenGL 3 renderer did not start");

  m_painter = std::make_unique<gl::Painter>();
  m_balloon_gpu = std::make_unique<gl::MeshBuffer>();
  m_marks_3d = std::make_unique<gl::LineBuffer>();
  m_tet_gpu = std::make_unique<gl::MeshBuffer>();
  m_drill_gpu = std::make_unique<gl::MeshBuffer>();
  m_deform_gpu = std::make_unique<gl::MeshBuffer>();
  m_grab_lines = std::make_unique<gl::LineBuffer>();
  m_tool_gpu = std::make_unique<gl::MeshBuffer>();
  m_force_lines = std::make_unique<gl::LineBuffer>();
  m_tool_mm = Vec3(0.5 * (m_bounds.min.x() + m_bounds.max.x()), 0.5 * (m_bounds.min.y() + m_bounds.max.y()),
                   m_bounds.max.z() + 2.0 * m_options.burr_radius_mm);
  move_tool(m_tool_mm);
  m_section_gpu = std::make_unique<gl::MeshBuffer>();
  m_section_lines = std::make_unique<gl::LineBuffer>();
  for (int a = 0; a < 3; ++a) {
    m_slice_2d[std::size_t(a)] = std::make_unique<gl::SliceQuad>();
    m_slice_3d[std::size_t(a)] = std::make_unique<gl::SliceQuad>();
    m_contours[std::size_t(a)] = std::make_unique<gl::LineBuffer>();
    m_marks[std::size_t(a)] = std::make_unique<gl::LineBuffer>();
    if (m_ct) upload_slice(a);
  }
  for (auto& o : m_objects) upload_object(o);
  frame_camera();
  if (m_ct && !m_options.seed_voxels.empty()) {
    for (const Index3& v : m_options.seed_voxels) m_placed.push_back({MarkKind::Seed, v});
    for (const Index3& v : m_options.stop_voxels) m_placed.push_back({MarkKind::Stop, v});
    const Index3& last = m_options.seed_voxels.back();
    for (int a = 0; a < 3; ++a) m_slice[std::size_t(a)] = last[std::size_t(a)];
    for (int a = 0; a < 3; ++a) upload_slice(a);
    restart_balloon();
  } else if (m_ct) {
    for (const Index3& v : m_options.stop_voxels) m_placed.push_back({MarkKind::Stop, v});
  }
}

void Workbench::frame_camera() { m_camera.frame(m_bounds.min, m_bounds.max); }

// ---- input ---------------------------------------------------------------------------------

void Workbench::on_input(InputEvent e) {
  if (m_script) return;  // a replay takes no live input
  e.frame = m_frame;
  if (!m_options.record.empty()) m_recorded.push_back(e);
  m_queue.push_back(std::move(e));
}

bool Workbench::condition_holds(const InputEvent& wait) {
  const std::string& until = wait.until;
  if (until == "deform_steps") {
    if (!m_deform) return true;
    const auto s = m_deform->latest();
    if (!m_wait_base_steps) m_wait_base_steps = s->steps;
    return s->steps >= *m_wait_base_steps + wait.steps || !s->error.empty();
  }
  if (save_running() || mesh_running() || drilling() || (m_deform && m_deform->busy())) return false;
  if (!m_session) return true;
  if (until == "segment_done") {
    const auto s = m_session->latest();
    return s->stage == SegmentStage::Done || s->stage == SegmentStage::Failed || s->stage == SegmentStage::Idle;
  }
  return !m_session->busy();
}

bool Workbench::feed_script() {
  const auto& events = m_script->events;
  if (m_next_event >= events.size() && m_queue.empty() && m_pending_screenshots.empty()) return false;
  while (m_next_event < events.size() && events[m_next_event].frame <= m_script_frame) {
    const InputEvent& e = events[m_next_event];
    if (e.kind == EventKind::Wait) {
      if (!m_wait_start) m_wait_start = Clock::now();
      if (!condition_holds(e)) {
        if (std::chrono::duration<double>(Clock::now() - *m_wait_start).count() > e.timeout_s)
          throw Error(fmt::format("{}: event {}: still waiting for '{}' after {} s", m_options.script.string(),
                                  m_next_event, e.until, e.timeout_s));
        return true;
      }
      m_wait_start.reset();
      m_wait_base_steps.reset();
    } else if (e.kind == EventKind::Quit) {
      return false;
    } else if (e.kind == EventKind::Screenshot) {
      m_pending_screenshots.push_back(e.name);
    } else {
      m_queue.push_back(e);
      if (!m_options.record.empty()) {  // recorded at the frame it was applied, as live input is
        m_recorded.push_back(e);
        m_recorded.back().frame = m_frame;
      }
    }
    ++m_next_event;
  }
  return true;
}

void Workbench::apply_input() {
  ImGuiIO& io = ImGui::GetIO();
  // Like Dear ImGui 1.87's input queue: a button or key that changes twice in one frame has
  // its second change (and everything after it) kept for the next frame, so quick clicks are
  // seen the same way live and replayed.
  std::array<bool, 3> button_changed = {false, false, false};
  std::vector<int> keys_changed;
  std::size_t used = 0;
  for (; used < m_queue.size(); ++used) {
    const InputEvent& e = m_queue[used];
    bool defer = false;
    switch (e.kind) {
      case EventKind::MouseMove:
        io.MousePos = ImVec2(float(e.x_px), float(e.y_px));
        view_mouse_move(e);
        break;
      case EventKind::MouseDown:
      case EventKind::MouseUp: {
        auto& changed = button_changed[std::size_t(std::clamp(e.button, 0, 2))];
        if (changed) {
          defer = true;
          break;
        }
        changed = true;
        if (e.x_px != m_mouse_x || e.y_px != m_mouse_y) {
          io.MousePos = ImVec2(float(e.x_px), float(e.y_px));
          InputEvent move = e;
          move.kind = EventKind::MouseMove;
          view_mouse_move(move);
        }
        io.MouseDown[e.button] = e.kind == EventKind::MouseDown;
        if (e.kind == EventKind::MouseDown)
          view_mouse_down(e);
        else
          view_mouse_up(e);
        break;
      }
      case EventKind::Scroll:
        io.MousePos = ImVec2(float(e.x_px), float(e.y_px));
        io.MouseWheel += float(e.scroll_y);
        view_scroll(e);
        break;
      case EventKind::KeyDown:
      case EventKind::KeyUp: {
        const int code = key_code(e.key);
        if (code < 0) break;
        if (std::find(keys_changed.begin(), keys_changed.end(), code) != keys_changed.end()) {
          defer = true;
          break;
        }
        keys_changed.push_back(code);
        io.KeysDown[code] = e.kind == EventKind::KeyDown;
        io.KeyCtrl = e.ctrl;
        io.KeyShift = e.shift;
        io.KeyAlt = e.alt;
        if (e.kind == EventKind::KeyDown) shortcut(e);
        break;
      }
      case EventKind::Char:
        io.AddInputCharacter(e.codepoint);
        break;
      default:
        break;
    }
    if (defer) break;
  }
  m_queue.erase(m_queue.begin(), m_queue.begin() + std::ptrdiff_t(used));
}

void Workbench::view_mouse_move(const InputEvent& e) {
  const double dx = e.x_px - m_mouse_x, dy = e.y_px - m_mouse_y;
  m_mouse_x = e.x_px;
  m_mouse_y = e.y_px;
  switch (m_drag) {
    case Drag::Rotate: m_camera.rotate(dx, dy); break;
    case Drag::Pan: m_camera.pan(dx, dy, m_rect_3d.height); break;
    case Drag::WindowLevel:
      m_window_width = std::max(1e-6, m_window_width * std::exp(0.005 * dx));
      m_level -= 0.002 * dy * m_window_width * 2.0;
      break;
    case Drag::Clip: {
      const double mm_per_px = 2.0 * m_camera.distance_mm() * std::tan(15.0 * kPi / 180.0) / std::max(1.0, m_rect_3d.height);
      m_clip_offset_mm -= dy * mm_per_px;
      m_clip_offset_mm = std::clamp(m_clip_offset_mm, m_bounds.min[m_clip_axis], m_bounds.max[m_clip_axis]);
      m_section_dirty = true;
      break;
    }
    case Drag::Tool: {
      // In the plane through the burr facing the camera: the burr follows the cursor.
      const viz::Camera cam = m_camera.camera();
      const Mat4 v = cam.view_matrix();
      const Vec3 right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
      const double depth = std::max(1.0, (m_tool_mm - cam.eye()).dot(-v.block<1, 3>(2, 0).transpose()));
      const double mm_per_px = 2.0 * depth * std::tan(0.5 * cam.fov_y_deg * kPi / 180.0) / std::max(1.0, m_rect_3d.height);
      move_tool(m_tool_mm + mm_per_px * (dx * right - dy * up));
      break;
    }
    case Drag::Grab: {
      const viz::Camera cam = m_camera.camera();
      const Mat4 v = cam.view_matrix();
      const Vec3 right = v.block<1, 3>(0, 0).transpose(), up = v.block<1, 3>(1, 0).transpose();
      const double depth = std::max(1.0, (m_grab.target_mm - cam.eye()).dot(-v.block<1, 3>(2, 0).transpose()));
      const double mm_per_px = 2.0 * depth * std::tan(0.5 * cam.fov_y_deg * kPi / 180.0) / std::max(1.0, m_rect_3d.height);
      m_grab.target_mm += mm_per_px * (dx * right - dy * up);
      m_deform->set_grab(m_grab);
      break;
    }
    case Drag::Roi: {
      const auto& view = m_slice_views[std::size_t(m_roi_axis)];
      if (!view) break;
      const PixelRect& r = view->rect();  // the cursor held inside the slice: the region stays in the volume
      const double x = std::clamp(e.x_px, r.x, r.x + r.width - 1), y = std::clamp(e.y_px, r.y, r.y + r.height - 1);
      if (const auto uv = view->voxel_at(x, y); uv && *uv != m_roi_to) {
        m_roi_to = *uv;
        m_contours_dirty = true;
      }
      break;
    }
    case Drag::None: break;
  }
}

void Workbench::view_mouse_down(const InputEvent& e) {
  if (m_capture_mouse || !m_view_area.contains(e.x_px, e.y_px)) return;
  if (m_rect_3d.contains(e.x_px, e.y_px)) {
    if (m_workspace == Workspace::Deform && e.button == 0 && m_deform) {
      grab(e.x_px, e.y_px);
      m_drag = m_grab.active ? Drag::Grab : Drag::Rotate;
    } else if (m_workspace == Workspace::Deform)
      m_drag = e.button == 1 ? Drag::Rotate : Drag::Pan;
    else if (m_workspace == Workspace::Drill)
      m_drag = e.button == 0 ? (m_drill && m_drill->source() && drilling() ? Drag::Rotate : Drag::Tool)
                             : e.button == 1 ? Drag::Rotate : Drag::Pan;
    else
      m_drag = e.button != 0 ? Drag::Pan : (m_workspace == Workspace::Mesh && m_clip_drag) ? Drag::Clip : Drag::Rotate;
    return;
  }
  for (int a = 0; a < 3; ++a) {
    const auto& v = m_slice_views[std::size_t(a)];
    if (!v || !v->rect().contains(e.x_px, e.y_px)) continue;
    if (e.button == 1) {
      m_drag = Drag::WindowLevel;
    } else if (e.button == 0 && (e.ctrl || m_drags_draw_roi)) {  // draw the region of interest
      if (const auto uv = v->voxel_at(e.x_px, e.y_px)) {
        m_drag = Drag::Roi;
        m_roi_axis = a;
        m_roi_from = m_roi_to = *uv;
        m_contours_dirty = true;
      }
    } else if (e.button == 0) {
      if (const auto uv = v->voxel_at(e.x_px, e.y_px)) {
        Index3 voxel;
        voxel[std::size_t(a)] = m_slice[std::size_t(a)];
        voxel[std::size_t(v->u_axis())] = (*uv)[0];
        voxel[std::size_t(v->v_axis())] = (*uv)[1];
        place_mark(e.shift || m_click_stops ? MarkKind::Stop : MarkKind::Seed, voxel);
      }
    }
  }
}

void Workbench::view_mouse_up(const InputEvent&) {
  if (m_drag == Drag::Roi && m_ct) {
    m_drag = Drag::None;
    set_roi(roi_of_drag());
    m_roi_axis = -1;
    return;
  }
  if (m_drag == Drag::Grab) {  // released: the spring goes, the body springs back
    m_grab.active = false;
    m_deform->set_grab(m_grab);
  }
  m_drag = Drag::None;
}

void Workbench::view_scroll(const InputEvent& e) {
  if (m_capture_mouse || !m_view_area.contains(e.x_px, e.y_px)) return;
  if (m_rect_3d.contains(e.x_px, e.y_px)) {
    if (m_workspace == Workspace::Drill) {  // the wheel moves the burr along the view: depth
      const Mat4 v = m_camera.camera().view_matrix();
      move_tool(m_tool_mm - 0.25 * m_options.burr_radius_mm * e.scroll_y * Vec3(v.block<1, 3>(2, 0).transpose()));
    } else {
      m_camera.zoom(e.scroll_y);
    }
    return;
  }
  for (int a = 0; a < 3; ++a) {
    const auto& v = m_slice_views[std::size_t(a)];
    if (v && v->rect().contains(e.x_px, e.y_px))
      set_slice(a, m_slice[std::size_t(a)] + static_cast<std::int64_t>(std::lround(e.scroll_y)));
  }
}

void Workbench::shortcut(const InputEvent& e) {
  if (m_capture_keyboard && !e.ctrl) return;
  const std::string& k = e.key;
  if (k == "f1" && m_ct) m_select_tab = Workspace::Segment;
  if (k == "f2") m_select_tab = Workspace::Scene;
  if (k == "f3") m_select_tab = Workspace::Mesh;
  if (k == "f4") m_select_tab = Workspace::Drill;
  if (k == "f5") m_select_tab = Workspace::Deform;
  if (k == "r" && !e.ctrl) frame_camera();
  if (k == "q" && e.ctrl && m_window) glfwSetWindowShouldClose(m_window, GLFW_TRUE);
  if (m_workspace == Workspace::Deform && m_deform) {
    if (k == "space") m_deform->set_running(!m_deform->running());
    if (k == "n" && !e.ctrl) m_deform->step_once();
    if (k == "m" && !e.ctrl) {
      m_field = static_cast<DeformField>((static_cast<int>(m_field) + 1) % 3);
      m_field_dirty = true;
    }
    if (k == "e" && !e.ctrl && !m_deform->parameters().empty()) m_focus_parameter = 0;  // edit the first parameter
    if (k == "i" && !e.ctrl && m_deform_state) {  // the next integrator, between steps
      const auto& names = m_deform->integrators();
      const auto it = std::find(names.begin(), names.end(), m_deform_state->integrator);
      m_deform->set_integrator(names[it == names.end() ? 0 : std::size_t(it - names.begin() + 1) % names.size()]);
    }
    return;
  }
  if (m_workspace == Workspace::Drill) {
    if (k == "d" && !e.ctrl) toggle_drilling();
    if (k == "p" && !e.ctrl) replay_path();
    if (k == "u" && !e.ctrl) connect_device();
    if ((k == "i" || k == "k") && !e.ctrl) turn_tool(k == "k" ? 15.0 : -15.0, 0.0);  // tilt the axis
    if ((k == "j" || k == "l") && !e.ctrl) turn_tool(0.0, k == "l" ? 15.0 : -15.0);  // turn it about z
    return;
  }
  if (m_workspace == Workspace::Mesh) {
    if (k == "t" && !e.ctrl) tetrahedralise();
    if (k == "c" && !e.ctrl) m_clip_drag = !m_clip_drag;
    if ((k == "x" || k == "y" || k == "z") && !e.ctrl) {
      m_clip_axis = k[0] - 'x';
      m_clip_offset_mm = 0.5 * (m_bounds.min[m_clip_axis] + m_bounds.max[m_clip_axis]);
      m_section_dirty = true;
    }
    if (k == "f" && !e.ctrl) {
      m_clip_flip = !m_clip_flip;
      m_section_dirty = true;
    }
    if (k == "s" && e.ctrl) save();
    return;
  }
  if (!m_ct || m_workspace != Workspace::Segment) return;
  if (k == "space") toggle_pause();
  if (k == "n" && !e.ctrl) step_once();
  if (k == "z" && e.ctrl) undo_mark();
  if (k == "x" && !e.ctrl) m_click_stops = !m_click_stops;
  if (k == "o" && !e.ctrl) m_drags_draw_roi = !m_drags_draw_roi;
  if (k == "enter" || k == "keypad_enter") accept();
  if (k == "s" && e.ctrl) save();
  if (k == "page_up" || k == "page_down") set_slice(2, m_slice[2] + (k == "page_up" ? 1 : -1));
}

// ---- actions -------------------------------------------------------------------------------

void Workbench::place_mark(MarkKind kind, const Index3& voxel) {
  if (!m_ct || !m_ct->contains(voxel[0], voxel[1], voxel[2])) return;
  m_placed.push_back({kind, voxel});
  for (int a = 0; a < 3; ++a) set_slice(a, voxel[std::size_t(a)]);
  const Vec3 w = m_ct->index_to_world(Vec3(double(voxel[0]), double(voxel[1]), double(voxel[2])));
  const auto n = std::count_if(m_placed.begin(), m_placed.end(), [kind](const Mark& m) { return m.kind == kind; });
  say(fmt::format("{} {} at voxel ({}, {}, {}) = ({:.3f}, {:.3f}, {:.3f}) mm", kind == MarkKind::Seed ? "seed" : "stop point",
                  n, voxel[0], voxel[1], voxel[2], w.x(), w.y(), w.z()));
  m_contours_dirty = true;
  restart_balloon();
}

std::vector<Vec3> Workbench::marks_mm(MarkKind kind) const {
  std::vector<Vec3> out;
  for (const Mark& m : m_placed)  // the world position as `ido segment --seed-voxel` computes it
    if (m.kind == kind) out.push_back(m_ct->index_to_world(Vec3(double(m.voxel[0]), double(m.voxel[1]), double(m.voxel[2]))));
  return out;
}

segment::BalloonChoices Workbench::balloon_choices() const {
  segment::BalloonChoices choices;  // what the panel says, as `ido segment`'s flags fill it
  choices.organ = m_organ;
  if (m_ct) choices.stop_points_mm = marks_mm(MarkKind::Stop);
  choices.roi_mm = m_roi_mm;
  choices.max_radius_mm = m_max_radius_mm;
  return choices;
}

geometry::Aabb Workbench::roi_of_drag() const {
  // The voxels from the first to the current one on the slice, edge to edge; across the slice
  // the region keeps its extent (the whole volume when there was none).
  const SliceView shape(m_roi_axis, m_ct->size(), m_ct->spacing(), {0, 0, 1, 1});
  const int a = m_roi_axis, u = shape.u_axis(), v = shape.v_axis();
  Vec3 lo, hi;
  lo[u] = double(std::min(m_roi_from[0], m_roi_to[0])) - 0.5;
  hi[u] = double(std::max(m_roi_from[0], m_roi_to[0])) + 0.5;
  lo[v] = double(std::min(m_roi_from[1], m_roi_to[1])) - 0.5;
  hi[v] = double(std::max(m_roi_from[1], m_roi_to[1])) + 0.5;
  lo[a] = -0.5;
  hi[a] = double(m_ct->size(a)) - 0.5;
  if (m_roi_mm) {
    const geometry::Aabb old = m_ct->index_bounds(*m_roi_mm);
    lo[a] = std::max(lo[a], old.min[a]);
    hi[a] = std::min(hi[a], old.max[a]);
    if (!(lo[a] < hi[a])) {  // the old region lies outside the volume along this axis
      lo[a] = -0.5;
      hi[a] = double(m_ct->size(a)) - 0.5;
    }
  }
  geometry::Aabb world;
  for (int c = 0; c < 8; ++c)
    world.extend(m_ct->index_to_world(Vec3((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z())));
  return world;
}

void Workbench::set_roi(std::optional<geometry::Aabb> roi_mm) {
  m_roi_mm = std::move(roi_mm);
  if (m_roi_mm)
    say(fmt::format("region of interest ({:.2f}, {:.2f}, {:.2f}) - ({:.2f}, {:.2f}, {:.2f}) mm", m_roi_mm->min.x(),
                    m_roi_mm->min.y(), m_roi_mm->min.z(), m_roi_mm->max.x(), m_roi_mm->max.y(), m_roi_mm->max.z()));
  else
    say("region of interest cleared");
  m_contours_dirty = true;
  restart_balloon();
}

void Workbench::restart_balloon() {
  if (!m_session) return;
  segment::BalloonOptions options;
  try {
    options = segment::balloon_options(balloon_choices());
  } catch (const InvalidInput& e) {  // a value the panel let through that the library refuses
    say(std::string("not started: ") + e.what());
    return;
  }
  const bool paused = m_session->paused();
  m_session->start(marks_mm(MarkKind::Seed), options, paused);
  m_contours_dirty = true;
}

void Workbench::undo_mark() {
  if (m_placed.empty()) return;
  const MarkKind kind = m_placed.back().kind;
  m_placed.pop_back();
  const auto n = std::count_if(m_placed.begin(), m_placed.end(), [kind](const Mark& m) { return m.kind == kind; });
  say(fmt::format("{} {} removed", kind == MarkKind::Seed ? "seed" : "stop point", n + 1));
  m_contours_dirty = true;
  restart_balloon();
}

void Workbench::toggle_pause() {
  if (!m_session) return;
  m_session->set_paused(!m_session->paused());
}

void Workbench::step_once() {
  if (m_session && m_session->paused()) m_session->step_once();
}

void Workbench::accept() {
  if (!m_state || m_state->stage != SegmentStage::Done || !m_state->result) {
    say("nothing to accept: the balloon has not finished");
    return;
  }
  ++m_accepted;
  SceneObject o;
  o.name = fmt::format("segmentation {}", m_accepted);
  o.mesh = m_state->result->surface;
  o.colour = kObjectColours[std::size_t(m_accepted) % kObjectColours.size()];
  upload_object(o);
  o.cull_back = closed_outward(o.mesh);
  m_objects.push_back(std::move(o));
  m_mesh_source = int(m_objects.size()) - 1;
  say(fmt::format("accepted segmentation {} ({} triangles)", m_accepted, m_state->result->surface.triangle_count()));
}

void Workbench::start_save(std::function<std::string()> work) {
  if (save_running()) return;
  if (m_save && m_save->thread.joinable()) m_save->thread.join();  // finished: does not wait
  m_save = std::make_unique<Job>();
  Job* job = m_save.get();
  job->thread = std::thread([job, work = std::move(work)] {
    try {
      job->message = "saved " + work();
      job->state.store(1, std::memory_order_release);
    } catch (const std::exception& e) {
      job->message = std::string("save failed: ") + e.what();
      job->state.store(2, std::memory_order_release);
    }
  });
  m_message = "saving...";
}

void Workbench::save() {
  if (m_workspace == Workspace::Mesh) {
    if (m_options.tet_output.empty()) {
      say("nothing to save to: start ido view with --tet-output");
    } else if (!m_mesh) {
      say("nothing to save: no tetrahedral mesh yet (t)");
    } else {
      std::shared_ptr<const MeshResult> mesh = m_mesh;
      const fs::path out = m_options.tet_output;
      start_save([mesh, out] {
        io::write_tet_mesh(out, mesh->mesh);
        return out.string();
      });
    }
    return;
  }
  const SegmentOutputs& out = m_options.segment_outputs;
  if (out.surface.empty() && out.mask.empty() && out.report.empty()) {
    say("nothing to save to: start ido view with --surface, --mask or --report");
    return;
  }
  if (!m_state || m_state->stage != SegmentStage::Done || !m_state->result) {
    say("nothing to save: the balloon has not finished");
    return;
  }
  SegmentRequest request{m_ct_name, m_state->seeds_mm, m_organ, m_state->options};  // with the run's stop points
  std::shared_ptr<const segment::BalloonResult> result = m_state->result;
  std::shared_ptr<const image::Volume<float>> ct = m_ct;
  start_save([out, request, result, ct] {
    save_segmentation(out, *ct, request, *result);
    std::string written;
    for (const fs::path* p : {&out.surface, &out.mask, &out.report})
      if (!p->empty()) written += (written.empty() ? "" : ", ") + p->string();
    return written;
  });
}

void Workbench::tetrahedralise() {
  if (mesh_running()) return;
  if (m_mesh_source < 0 || m_mesh_source >= int(m_objects.size())) {
    say("nothing to tetrahedralise: open a closed surface or accept a segmentation");
    return;
  }
  if (m_mesh_job && m_mesh_job->thread.joinable()) m_mesh_job->thread.join();  // finished: does not wait
  const SceneObject& o = m_objects[std::size_t(m_mesh_source)];
  m_mesh_job = std::make_unique<Job>();
  Job* job = m_mesh_job.get();
  auto result = std::make_shared<MeshResult>();
  m_mesh_pending = result;
  result->source = o.name;
  std::shared_ptr<const geometry::TetMesh> tets = o.tets;
  geometry::TriangleMesh surface = tets ? geometry::TriangleMesh{} : o.mesh;
  const double edge_mm = m_tet_edge_mm;
  job->thread = std::thread([job, result, tets, surface = std::move(surface), edge_mm] {
    try {
      if (tets) {
        result->mesh = *tets;
      } else {
        // As `ido tetmesh SURFACE`: a closed surface filled by isosurface stuffing.
        const auto check = geometry::check_mesh(surface);
        if (surface.triangles.empty() || check.boundary_edges > 0 || check.non_manifold_edges > 0)
          throw InvalidInput(fmt::format("the surface is not closed ({} boundary edges, {} non-manifold edges)",
                                         check.boundary_edges, check.non_manifold_edges));
        meshing::TetrahedralizeOptions to;
        to.edge_mm = edge_mm;
        result->mesh = meshing::tetrahedralize_surface(surface, to);
        if (result->mesh.tets.empty()) throw InvalidInput("nothing to mesh: the surface is thinner than the lattice spacing");
      }
      result->report = geometry::check_tet_mesh(result->mesh);
      result->histogram = dihedral_histogram(result->mesh, 36);
      result->boundary = geometry::tet_boundary(result->mesh);
      job->message = fmt::format("{}: {} tetrahedra", result->source, result->mesh.tets.size());
      job->state.store(1, std::memory_order_release);
    } catch (const std::exception& e) {
      job->message = std::string("tetrahedralisation failed: ") + e.what();
      job->state.store(2, std::memory_order_release);
    }
  });
  m_message = "tetrahedralising...";
}

viz::ClipPlane Workbench::clip_plane() const {
  // The half toward the camera is cut away (flip keeps it instead), so the section faces the user.
  viz::ClipPlane p;
  const double toward_eye = m_camera.camera().direction[m_clip_axis] >= 0 ? 1.0 : -1.0;
  p.normal = (m_clip_flip ? -toward_eye : toward_eye) * Vec3::Unit(m_clip_axis);
  p.point = Vec3::Zero();
  p.point[m_clip_axis] = m_clip_offset_mm;
  return p;
}

void Workbench::rebuild_section() {
  m_section_dirty = false;
  if (!m_mesh) return;
  m_section_normal = clip_plane().normal;
  const TetSection section = tet_section(m_mesh->mesh, clip_plane());
  m_section_gpu->upload(section.faces, kSectionColour);
  m_section_lines->clear();
  for (const auto& e : section.edges) m_section_lines->add(e[0], e[1], kSectionEdgeColour);
  m_section_lines->upload();
  m_cut_tets = section.cut_tets;
}

void Workbench::set_slice(int axis, std::int64_t index) {
  if (!m_ct) return;
  index = std::clamp<std::int64_t>(index, 0, m_ct->size(axis) - 1);
  if (index == m_slice[std::size_t(axis)]) return;
  m_slice[std::size_t(axis)] = index;
  upload_slice(axis);
  m_contours_dirty = true;
}

// ---- frame ---------------------------------------------------------------------------------

void Workbench::upload_slice(int axis) {
  const image::Volume<float>& ct = *m_ct;
  const SliceView shape(axis, ct.size(), ct.spacing(), {0, 0, 1, 1});
  const int u = shape.u_axis(), v = shape.v_axis();
  const std::int64_t nu = ct.size(u), nv = ct.size(v), s = m_slice[std::size_t(axis)];
  std::vector<float> values(std::size_t(nu * nv));
  Index3 idx;
  idx[std::size_t(axis)] = s;
  for (std::int64_t b = 0; b < nv; ++b)
    for (std::int64_t a = 0; a < nu; ++a) {
      idx[std::size_t(u)] = a;
      idx[std::size_t(v)] = b;
      values[std::size_t(b * nu + a)] = ct(idx[0], idx[1], idx[2]);
    }
  auto& q2 = *m_slice_2d[std::size_t(axis)];
  auto& q3 = *m_slice_3d[std::size_t(axis)];
  q2.upload_image(int(nu), int(nv), values);
  q3.upload_image(int(nu), int(nv), values);
  auto corner = [&](double cu, double cv) {
    Vec3 c;
    c[axis] = double(s);
    c[u] = cu;
    c[v] = cv;
    return c;
  };
  const double u0 = -0.5, u1 = double(nu) - 0.5, v0 = -0.5, v1 = double(nv) - 0.5;
  q2.set_corners({Vec3(u0, v0, 0), Vec3(u1, v0, 0), Vec3(u1, v1, 0), Vec3(u0, v1, 0)});
  q3.set_corners({ct.index_to_world(corner(u0, v0)), ct.index_to_world(corner(u1, v0)),
                  ct.index_to_world(corner(u1, v1)), ct.index_to_world(corner(u0, v1))});
}

void Workbench::rebuild_contours() {
  m_contours_dirty = false;
  if (!m_ct) return;
  const geometry::TriangleMesh* surface = m_state ? &m_state->surface : nullptr;
  std::vector<Vec3> idx;
  if (surface) {
    idx.reserve(surface->vertices.size());
    for (const Vec3& p : surface->vertices) idx.push_back(m_ct->world_to_index(p));
  }
  // The region of interest in voxel indices (the one being drawn, else the one set).
  std::optional<geometry::Aabb> roi;
  if (m_drag == Drag::Roi && m_roi_axis >= 0)
    roi = m_ct->index_bounds(roi_of_drag());
  else if (m_roi_mm)
    roi = m_ct->index_bounds(*m_roi_mm);
  for (int a = 0; a < 3; ++a) {
    const SliceView shape(a, m_ct->size(), m_ct->spacing(), {0, 0, 1, 1});
    const int u = shape.u_axis(), v = shape.v_axis();
    const double s = double(m_slice[std::size_t(a)]);
    auto& lines = *m_contours[std::size_t(a)];
    lines.clear();
    if (surface)
      for (const Tri& t : surface->triangles) {
        std::array<Vec3, 2> cut;
        int n = 0;
        for (int e = 0; e < 3 && n < 2; ++e) {
          const Vec3& p = idx[std::size_t(t[std::size_t(e)])];
          const Vec3& q = idx[std::size_t(t[std::size_t((e + 1) % 3)])];
          const double dp = p[a] - s, dq = q[a] - s;
          if ((dp < 0) == (dq < 0)) continue;
          const Vec3 x = p + (dp / (dp - dq)) * (q - p);
          cut[std::size_t(n++)] = Vec3(x[u], x[v], 0);
        }
        if (n == 2) lines.add(cut[0], cut[1], kContourColour);
      }
    lines.upload();
    // Marks: the other slices (crosshair) and the seeds on this slice.
    auto& marks = *m_marks[std::size_t(a)];
    marks.clear();
    const double nu = double(m_ct->size(u)), nv = double(m_ct->size(v));
    const double cu = double(m_slice[std::size_t(u)]), cv = double(m_slice[std::size_t(v)]);
    marks.add(Vec3(cu, -0.5, 0), Vec3(cu, nv - 0.5, 0), 0.5 * kCrosshairColour);
    marks.add(Vec3(-0.5, cv, 0), Vec3(nu - 0.5, cv, 0), 0.5 * kCrosshairColour);
    for (const Mark& m : m_placed) {
      const Index3& sv = m.voxel;
      if (sv[std::size_t(a)] != m_slice[std::size_t(a)]) continue;
      const double su = double(sv[std::size_t(u)]), sw = double(sv[std::size_t(v)]);
      const double r = 2.0;
      if (m.kind == MarkKind::Seed) {  // a cross
        marks.add(Vec3(su - r, sw, 0), Vec3(su + r, sw, 0), kSeedColour);
        marks.add(Vec3(su, sw - r, 0), Vec3(su, sw + r, 0), kSeedColour);
      } else {  // an X
        marks.add(Vec3(su - r, sw - r, 0), Vec3(su + r, sw + r, 0), kStopColour);
        marks.add(Vec3(su - r, sw + r, 0), Vec3(su + r, sw - r, 0), kStopColour);
      }
    }
    if (roi) {  // the region's rectangle where this slice crosses it
      const geometry::Aabb& b = *roi;
      if (double(m_slice[std::size_t(a)]) >= b.min[a] && double(m_slice[std::size_t(a)]) <= b.max[a]) {
        const Vec3 p00(b.min[u], b.min[v], 0), p10(b.max[u], b.min[v], 0), p11(b.max[u], b.max[v], 0), p01(b.min[u], b.max[v], 0);
        marks.add(p00, p10, kRoiColour);
        marks.add(p10, p11, kRoiColour);
        marks.add(p11, p01, kRoiColour);
        marks.add(p01, p00, kRoiColour);
      }
    }
    marks.upload();
  }
  m_marks_3d->clear();
  if (roi) {  // the region's twelve edges in the 3-D view
    const geometry::Aabb& b = *roi;
    auto corner = [&](int c) {
      return m_ct->index_to_world(Vec3((c & 1) ? b.max.x() : b.min.x(), (c & 2) ? b.max.y() : b.min.y(), (c & 4) ? b.max.z() : b.min.z()));
    };
    for (int c = 0; c < 8; ++c)
      for (int bit : {1, 2, 4})
        if (!(c & bit)) m_marks_3d->add(corner(c), corner(c | bit), kRoiColour);
  }
  const double r = 3.0 * m_ct->spacing().minCoeff();
  for (const Mark& m : m_placed) {
    const Vec3 w = m_ct->index_to_world(Vec3(double(m.voxel[0]), double(m.voxel[1]), double(m.voxel[2])));
    for (int c = 0; c < 3; ++c)
      m_marks_3d->add(w - r * Vec3::Unit(c), w + r * Vec3::Unit(c), m.kind == MarkKind::Seed ? kSeedColour : kStopColour);
  }
  m_marks_3d->upload();
}

void Workbench::layout(double width, double height) {
  m_view_area = {m_panel_px, 0, std::max(1.0, width - m_panel_px), height};
  const PixelRect& a = m_view_area;
  if (m_workspace == Workspace::Segment && m_ct) {
    const double hw = std::floor(a.width / 2), hh = std::floor(a.height / 2);
    const PixelRect axial{a.x, a.y, hw, hh}, three{a.x + hw, a.y, a.width - hw, hh};
    const PixelRect coronal{a.x, a.y + hh, hw, a.height - hh}, sagittal{a.x + hw, a.y + hh, a.width - hw, a.height - hh};
    m_rect_3d = three;
    m_slice_views[2].emplace(2, m_ct->size(), m_ct->spacing(), axial);
    m_slice_views[1].emplace(1, m_ct->size(), m_ct->spacing(), coronal);
    m_slice_views[0].emplace(0, m_ct->size(), m_ct->spacing(), sagittal);
  } else {
    m_rect_3d = a;
    if (m_workspace == Workspace::Deform) m_rect_3d.width = std::max(1.0, a.width - 120.0);  // room for the colour bar
    for (auto& v : m_slice_views) v.reset();
  }
}

void Workbench::update_from_workers() {
  if (m_session) {
    auto s = m_session->latest();
    if (s != m_state) {
      m_state = std::move(s);
      m_balloon_gpu->upload(m_state->surface, kBalloonColour);
      m_contours_dirty = true;
    }
  }
  if (m_save && m_save->state.load(std::memory_order_acquire) != 0 && m_save->thread.joinable()) {
    m_save->thread.join();  // it has finished: this does not wait
    say(m_save->message);
  }
  if (m_mesh_job && m_mesh_job->state.load(std::memory_order_acquire) != 0 && m_mesh_job->thread.joinable()) {
    m_mesh_job->thread.join();  // it has finished: this does not wait
    if (m_mesh_job->state.load() == 1) {
      m_mesh = std::move(m_mesh_pending);
      m_tet_gpu->upload(m_mesh->boundary, kObjectColours[1]);
      m_section_dirty = true;
    }
    m_mesh_pending.reset();
    say(m_mesh_job->message);
  }
  if (m_drill) {
    if (auto snap = m_drill->latest_surface(); snap && snap != m_drill_surface) {
      m_drill_surface = std::move(snap);
      m_drill_gpu->upload(m_drill_surface->surface, kMaterialColour, /*flat=*/true);
    }
    m_figures = m_drill->figures();
    if (m_drill->source() && m_drill->started() && m_figures.ticks > 0) {  // the tool follows the path or the device
      const drill::ToolPose pose = m_drill->tool_pose();
      if (pose.position_mm != m_tool_mm || pose.orientation.coeffs() != m_tool_shown.coeffs()) {
        m_tool_mm = pose.position_mm;
        m_tool_shown = pose.orientation;
        draw_tool(pose);
      }
    }
    if (m_figures.force_n != m_force_shown_n || m_tool_mm != m_force_at_mm) {
      m_force_shown_n = m_figures.force_n;
      m_force_at_mm = m_tool_mm;
      m_force_lines->clear();
      m_force_lines->add(m_tool_mm, m_tool_mm + 2.0 * m_figures.force_n, kForceColour);  // 2 mm per newton
      m_force_lines->upload();
    }
    if (m_drill->started() && m_drill->ended() && !m_drill_reported && m_drill_surface && m_drill_surface->final) drill_ended();
  }
  if (m_deform) update_deform();
  if (m_contours_dirty) rebuild_contours();
  if (m_mesh && clip_plane().normal != m_section_normal) m_section_dirty = true;  // the camera turned past the plane
  if (m_section_dirty) rebuild_section();
}

void Workbench::panel() {
  ImGuiIO& io = ImGui::GetIO();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(float(kPanelWidthPx), io.DisplaySize.y));
  ImGui::Begin("ido view", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoBringToFrontOnFocus);
  if (ImGui::BeginTabBar("workspaces")) {
    auto flags = [&](Workspace w) {
      return m_select_tab == w ? ImGuiTabItemFlags_SetSelected : ImGuiTabItemFlags_None;
    };
    if (m_ct && ImGui::BeginTabItem("Segment", nullptr, flags(Workspace::Segment))) {
      m_workspace = Workspace::Segment;
      const SegmentState& s = *m_state;
      ImGui::TextWrapped("%s", m_ct_name.c_str());
      ImGui::Text("%lld x %lld x %lld voxels, %.3g x %.3g x %.3g mm", static_cast<long long>(m_ct->size(0)),
                  static_cast<long long>(m_ct->size(1)), static_cast<long long>(m_ct->size(2)), m_ct->spacing().x(),
                  m_ct->spacing().y(), m_ct->spacing().z());
      int organ = static_cast<int>(m_organ);
      const char* organs[] = {"generic", "artery", "vein", "vertebra"};
      if (ImGui::Combo("organ", &organ, organs, 4) && organ != static_cast<int>(m_organ)) {
        m_organ = static_cast<segment::Organ>(organ);
        restart_balloon();
      }
      ImGui::Separator();
      ImGui::Text("balloon: %s, %lld steps", segment_stage_name(s.stage), static_cast<long long>(s.steps));
      ImGui::Text("%zu vertices, %zu triangles", s.surface.vertex_count(), s.surface.triangle_count());
      if (s.result) {
        ImGui::Text("volume %.1f mm3, Euler %lld, %s", s.result->report.volume_mm3,
                    static_cast<long long>(s.result->report.euler_characteristic), s.result->report.stop_reason.c_str());
        for (const segment::LeakEvent& e : s.result->report.leaks)
          ImGui::Text("leak stopped (%s) at (%.1f, %.1f, %.1f) mm", segment::leak_cause_name(e.cause), e.position_mm.x(),
                      e.position_mm.y(), e.position_mm.z());
      }
      if (s.stage == SegmentStage::Failed) ImGui::TextWrapped("error: %s", s.error.c_str());
      if (ImGui::Button(m_session->paused() ? "Resume (space)" : "Pause (space)")) toggle_pause();
      ImGui::SameLine();
      if (ImGui::Button("Step (n)")) step_once();
      if (ImGui::Button("Undo (ctrl+z)")) undo_mark();
      ImGui::SameLine();
      if (ImGui::Button("Accept (enter)")) accept();
      if (ImGui::Button("Save (ctrl+s)")) save();
      ImGui::Separator();
      ImGui::TextWrapped("click a slice: a seed (green +); shift+click: a stop point (blue x), which the front does not pass");
      ImGui::Checkbox("clicks place stop points (x)", &m_click_stops);
      roi_panel();
      int seeds = 0, stops = 0;
      for (const Mark& m : m_placed) {
        const Index3& v = m.voxel;
        const Vec3 w = m_ct->index_to_world(Vec3(double(v[0]), double(v[1]), double(v[2])));
        ImGui::Text("%s %d: (%lld, %lld, %lld) = (%.1f, %.1f, %.1f) mm", m.kind == MarkKind::Seed ? "seed" : "stop",
                    m.kind == MarkKind::Seed ? ++seeds : ++stops, static_cast<long long>(v[0]),
                    static_cast<long long>(v[1]), static_cast<long long>(v[2]), w.x(), w.y(), w.z());
      }
      ImGui::Separator();
      float window = float(m_window_width), level = float(m_level);
      if (ImGui::DragFloat("window", &window, float(0.005 * m_window_width), 1e-3f, 1e6f)) m_window_width = window;
      if (ImGui::DragFloat("level", &level, float(0.005 * m_window_width))) m_level = level;
      for (int a = 2; a >= 0; --a) {
        int index = int(m_slice[std::size_t(a)]);
        if (ImGui::SliderInt(kAxisNames[std::size_t(a)], &index, 0, int(m_ct->size(a) - 1))) set_slice(a, index);
      }
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Scene", nullptr, flags(Workspace::Scene))) {
      m_workspace = Workspace::Scene;
      if (m_objects.empty()) ImGui::TextWrapped("no surfaces: open surfaces, tetrahedral meshes or scenes, or accept a segmentation");
      for (auto& o : m_objects) {
        ImGui::Checkbox(o.name.c_str(), &o.visible);
        ImGui::SameLine();
        ImGui::TextDisabled("%zu triangles", o.mesh.triangle_count());
      }
      if (ImGui::Button("Reset camera (r)")) frame_camera();
      ImGui::EndTabItem();
    }
    if (m_deform && ImGui::BeginTabItem("Deform", nullptr, flags(Workspace::Deform))) {
      m_workspace = Workspace::Deform;
      deform_panel();
      ImGui::EndTabItem();
    }
    if (drill_material() && ImGui::BeginTabItem("Drill", nullptr, flags(Workspace::Drill))) {
      m_workspace = Workspace::Drill;
      drill_panel();
      ImGui::EndTabItem();
    }
    if (ImGui::BeginTabItem("Mesh", nullptr, flags(Workspace::Mesh))) {
      m_workspace = Workspace::Mesh;
      mesh_panel();
      ImGui::EndTabItem();
    }
    ImGui::EndTabBar();
  }
  m_select_tab.reset();
  ImGui::Separator();
  if (!m_message.empty()) ImGui::TextWrapped("%s", m_message.c_str());
  std::vector<double> ms = m_frame_ms;
  if (!ms.empty()) {
    std::nth_element(ms.begin(), ms.begin() + std::ptrdiff_t(ms.size() / 2), ms.end());
    ImGui::TextDisabled("frame %.1f ms (median of %zu)", ms[ms.size() / 2], ms.size());
  }
  ImGui::End();
}

void Workbench::roi_panel() {
  ImGui::Separator();
  ImGui::TextWrapped("region of interest (the balloon deflates outside it): ctrl+drag on a slice");
  ImGui::Checkbox("drags draw the region (o)", &m_drags_draw_roi);
  if (m_roi_mm) {
    std::array<float, 3> lo = {float(m_roi_mm->min.x()), float(m_roi_mm->min.y()), float(m_roi_mm->min.z())};
    std::array<float, 3> hi = {float(m_roi_mm->max.x()), float(m_roi_mm->max.y()), float(m_roi_mm->max.z())};
    const float step = float(0.25 * m_ct->spacing().minCoeff());
    ImGui::DragFloat3("min (mm)", lo.data(), step, 0.0f, 0.0f, "%.1f");
    const bool lo_done = ImGui::IsItemDeactivatedAfterEdit();
    ImGui::DragFloat3("max (mm)", hi.data(), step, 0.0f, 0.0f, "%.1f");
    const bool hi_done = ImGui::IsItemDeactivatedAfterEdit();
    if (lo_done || hi_done) {  // applied when the field is let go: one balloon restart per edit
      geometry::Aabb b{Vec3(lo[0], lo[1], lo[2]), Vec3(hi[0], hi[1], hi[2])};
      if ((b.min.array() < b.max.array()).all())
        set_roi(b);
      else
        say("the region's minimum must be below its maximum on every axis");
    }
    if (ImGui::Button("Clear region")) set_roi(std::nullopt);
  } else {
    ImGui::TextDisabled("none");
  }
  bool bounded = m_max_radius_mm.has_value();
  if (ImGui::Checkbox("bound the local radius", &bounded)) {
    m_max_radius_mm = bounded ? std::optional<double>(10.0 * m_ct->spacing().maxCoeff()) : std::nullopt;
    restart_balloon();
  }
  if (m_max_radius_mm) {
    double r = *m_max_radius_mm;
    if (ImGui::InputDouble("max radius (mm)", &r, 0.5, 2.0, "%.2f", ImGuiInputTextFlags_EnterReturnsTrue) && r > 0 &&
        std::isfinite(r) && r != *m_max_radius_mm) {
      m_max_radius_mm = r;
      restart_balloon();
    }
  }
}

void Workbench::mesh_panel() {
  std::vector<const char*> names;
  for (const auto& o : m_objects) names.push_back(o.name.c_str());
  if (names.empty()) {
    ImGui::TextWrapped("nothing to mesh: open a closed surface or a tetrahedral mesh, or accept a segmentation");
  } else {
    int source = std::max(0, m_mesh_source);
    if (ImGui::Combo("source", &source, names.data(), int(names.size()))) m_mesh_source = source;
  }
  float edge = float(m_tet_edge_mm);
  if (ImGui::DragFloat("edge (mm)", &edge, 0.05f, 0.0f, 100.0f, edge > 0 ? "%.2f" : "auto")) m_tet_edge_mm = std::max(0.0f, edge);
  if (ImGui::Button(mesh_running() ? "Tetrahedralising..." : "Tetrahedralise (t)")) tetrahedralise();
  ImGui::SameLine();
  if (ImGui::Button("Save (ctrl+s)")) save();
  if (!m_mesh) return;
  const geometry::TetMeshReport& q = m_mesh->report;
  ImGui::Separator();
  ImGui::TextWrapped("%s", m_mesh->source.c_str());
  ImGui::Text("%zu tetrahedra, %zu vertices", q.tets, q.vertices);
  ImGui::Text("%zu boundary faces, volume %.1f mm3", q.boundary_faces, q.volume_mm3);
  ImGui::Text("inverted %zu, degenerate %zu", q.inverted, q.degenerate);
  ImGui::Text("dihedral angles %.2f - %.2f deg", q.min_dihedral_deg, q.max_dihedral_deg);
  std::vector<float> bins(m_mesh->histogram.begin(), m_mesh->histogram.end());
  ImGui::PlotHistogram("##dihedral", bins.data(), int(bins.size()), 0, "dihedral angles, 0-180 deg (5 deg bins)", 0.0f,
                       FLT_MAX, ImVec2(ImGui::GetContentRegionAvail().x, 90));
  ImGui::Separator();
  ImGui::Text("clip plane (cuts through tetrahedra):");
  int axis = m_clip_axis;
  ImGui::RadioButton("x", &axis, 0);
  ImGui::SameLine();
  ImGui::RadioButton("y", &axis, 1);
  ImGui::SameLine();
  ImGui::RadioButton("z", &axis, 2);
  ImGui::SameLine();
  if (ImGui::Checkbox("flip (f)", &m_clip_flip)) m_section_dirty = true;
  if (axis != m_clip_axis) {
    m_clip_axis = axis;
    m_clip_offset_mm = 0.5 * (m_bounds.min[axis] + m_bounds.max[axis]);
    m_section_dirty = true;
  }
  float offset = float(m_clip_offset_mm);
  if (ImGui::SliderFloat("at (mm)", &offset, float(m_bounds.min[m_clip_axis]), float(m_bounds.max[m_clip_axis]))) {
    m_clip_offset_mm = offset;
    m_section_dirty = true;
  }
  ImGui::Checkbox("drag moves the plane (c)", &m_clip_drag);
  ImGui::Text("%zu tetrahedra cut", m_cut_tets);
}

std::shared_ptr<const geometry::TetMesh> Workbench::drill_material() const {
  if (m_mesh) return std::shared_ptr<const geometry::TetMesh>(m_mesh, &m_mesh->mesh);  // shares the mesh result
  for (const auto& o : m_objects)
    if (o.tets) return o.tets;
  return nullptr;
}

Eigen::Quaterniond Workbench::tool_orientation() const {
  // The shaft (the tool's +z) tilted by m_tool_tilt_deg from +z towards +x, then turned by
  // m_tool_azimuth_deg about +z.
  return Eigen::Quaterniond(Eigen::AngleAxisd(m_tool_azimuth_deg * kPi / 180.0, Vec3::UnitZ()) *
                            Eigen::AngleAxisd(m_tool_tilt_deg * kPi / 180.0, Vec3::UnitY()));
}

void Workbench::move_tool(const Vec3& position_mm) {
  m_tool_mm = position_mm;
  drill::ToolPose pose;
  pose.position_mm = position_mm;
  pose.orientation = tool_orientation();
  if (m_drill && drilling()) m_drill->set_tool_pose(pose);
  draw_tool(pose);
}

void Workbench::draw_tool(const drill::ToolPose& pose) {
  if (!m_tool_gpu) return;
  geometry::TriangleMesh tool = segment::balloon_icosphere(pose.position_mm, m_options.burr_radius_mm, 2);
  // The shaft: a cylinder along the tool's axis from the burr centre (drill::ToolOptions' length);
  // without one, a thin stub shows the axis.
  const double r = m_options.shaft_radius_mm > 0 ? m_options.shaft_radius_mm : 0.15 * m_options.burr_radius_mm;
  const double length = m_options.shaft_radius_mm > 0 ? drill::ToolOptions{}.shaft_length_mm : 2.5 * m_options.burr_radius_mm;
  const Mat3 rot = pose.orientation.toRotationMatrix();
  constexpr int kSides = 16;
  const auto base = std::int32_t(tool.vertices.size());
  for (int i = 0; i < kSides; ++i) {
    const double a = 2 * kPi * i / kSides;
    for (double z : {0.0, length}) tool.vertices.push_back(pose.position_mm + rot * Vec3(r * std::cos(a), r * std::sin(a), z));
  }
  for (int i = 0; i < kSides; ++i) {
    const std::int32_t a0 = base + 2 * i, a1 = a0 + 1, b0 = base + 2 * ((i + 1) % kSides), b1 = b0 + 1;
    tool.triangles.push_back({a0, b0, b1});
    tool.triangles.push_back({a0, b1, a1});
  }
  m_tool_gpu->upload(tool, kToolColour);
}

void Workbench::turn_tool(double tilt_deg, double azimuth_deg) {
  m_tool_tilt_deg = std::clamp(m_tool_tilt_deg + tilt_deg, 0.0, 180.0);
  m_tool_azimuth_deg = std::remainder(m_tool_azimuth_deg + azimuth_deg, 360.0);
  move_tool(m_tool_mm);
}

void Workbench::toggle_drilling() {
  if (drilling()) {
    m_drill->stop();
    m_message = "stopping: finishing the erosion backlog...";
    return;
  }
  start_drilling(nullptr, m_options.drill_max_s, "mouse");
}

void Workbench::start_drilling(std::unique_ptr<drill::HapticDevice> source, double max_duration_s, const std::string& what) {
  if (drilling()) {
    say("a drilling session is running: stop it first (d)");
    return;
  }
  const auto material = drill_material();
  if (!material) return;
  try {
    drill::SimulatorOptions so = drill_cli_options(m_options.burr_radius_mm, m_options.shaft_radius_mm);
    // The collision thread at real-time priority below the haptic thread's: the frame loop and
    // the software rasteriser's threads then cannot delay its updates (bench/results/view.md;
    // refused without CAP_SYS_NICE, then it runs as in `ido drill`).
    so.collision_realtime_priority = kCollisionPriority;
    m_drill = std::make_unique<DrillSession>(*material, so, max_duration_s, std::move(source));
  } catch (const std::exception& e) {
    say(std::string("cannot drill: ") + e.what());
    return;
  }
  m_drill_reported = false;
  m_drill_surface.reset();
  m_drill_source = what;
  drill::ToolPose pose;
  pose.position_mm = m_tool_mm;
  pose.orientation = tool_orientation();
  m_drill->start(pose);
  say(fmt::format("drilling ({}): burr radius {} mm, at most {:.4g} s", what, m_options.burr_radius_mm, max_duration_s));
}

void Workbench::replay_path() {
  const fs::path csv(m_replay_path.data());
  if (csv.empty()) {
    say("nothing to replay: give a path CSV (--drill-replay, or the panel's field)");
    return;
  }
  std::unique_ptr<drill::ScriptedTrajectory> device;
  try {
    device = load_path_device(csv, drill_cli_options(m_options.burr_radius_mm, m_options.shaft_radius_mm));
  } catch (const std::exception& e) {
    say(std::string("cannot replay: ") + e.what());
    return;
  }
  // The session ends with the path (and its erosion backlog), as `ido drill --path` does.
  const double duration = std::min(device->duration() + 1.0, drill::kMaxScriptDuration_s);
  start_drilling(std::move(device), duration, "path:" + csv.string());
}

void Workbench::connect_device() {
  std::unique_ptr<drill::UdpBridge> bridge;
  try {
    drill::UdpBridgeOptions o;
    o.port = static_cast<std::uint16_t>(m_options.drill_udp_port);
    bridge = std::make_unique<drill::UdpBridge>(o);
  } catch (const std::exception& e) {
    say(std::string("cannot open the device bridge: ") + e.what());
    return;
  }
  const std::uint16_t port = bridge->port();
  start_drilling(std::move(bridge), m_options.drill_max_s, fmt::format("udp:{}", port));
}

void Workbench::drill_ended() {
  m_drill_reported = true;
  const drill::SessionStats& st = m_drill->stats();
  auto ms = [](const std::vector<double>& s) {
    std::vector<double> v(s);
    for (double& x : v) x *= 1e3;
    return drill::percentiles(std::move(v));
  };
  const drill::Percentiles update = ms(st.update_time_s), period = ms(st.haptic_period_s);
  m_drill_summary = fmt::format(
      "removed {:.2f} mm3 in {} ticks\nupdate p50 {:.2f} / p99 {:.2f} ms\nhaptic period p50 {:.3f} / p99 {:.3f} / "
      "p99.9 {:.3f} ms\nmissed deadlines: {}\nreal-time priority: haptic {}, collision {}",
      st.removed_volume_mm3, st.haptic_ticks, update.p50, update.p99, period.p50, period.p99, period.p999,
      st.missed_deadlines, st.haptic_realtime ? "yes" : "refused", st.collision_realtime ? "yes" : "refused");
  say(fmt::format("drilling ended: removed {:.3f} mm3", st.removed_volume_mm3));
  try {
    if (!m_options.drill_path.empty()) m_drill->write_path_csv(m_options.drill_path);
    if (!m_options.drill_report.empty()) {
      auto json_of = [](const drill::Percentiles& p) {
        return nlohmann::json{{"p50", p.p50}, {"p99", p.p99}, {"p999", p.p999}, {"max", p.max}, {"count", p.count}};
      };
      const nlohmann::json j = {{"burr_radius_mm", m_options.burr_radius_mm},
                                {"shaft_radius_mm", m_options.shaft_radius_mm},
                                {"source", m_drill_source},
                                {"initial_volume_mm3", m_drill->initial_volume_mm3()},
                                {"removed_volume_mm3", st.removed_volume_mm3},
                                {"haptic_ticks", st.haptic_ticks},
                                {"missed_deadlines", st.missed_deadlines},
                                {"haptic_realtime", st.haptic_realtime},
                                {"collision_realtime", st.collision_realtime},
                                {"collision_updates", st.collision_updates},
                                {"peak_force_n", st.peak_force_n},
                                {"update_time_ms", json_of(update)},
                                {"haptic_period_ms", json_of(period)},
                                {"force_compute_ms", json_of(ms(st.force_compute_time_s))},
                                {"path", m_options.drill_path.empty() ? nlohmann::json(nullptr)
                                                                      : nlohmann::json(m_options.drill_path.string())}};
      const std::string text = j.dump(2) + "\n";
      write_file_atomically(m_options.drill_report, [&](std::ostream& out) { out << text; }, false);
    }
  } catch (const std::exception& e) {
    say(std::string("drilling outputs failed: ") + e.what());
  }
}

void Workbench::drill_panel() {
  ImGui::TextWrapped("left drag: move the burr in the view's plane; wheel: depth; right drag: turn; d: start / stop");
  const bool running = drilling();
  if (ImGui::Button(running ? "Stop (d)" : "Start drilling (d)")) toggle_drilling();
  ImGui::Separator();
  ImGui::Text("path CSV to replay (as ido drill --path):");
  ImGui::PushItemWidth(-1);
  ImGui::InputText("##replay", m_replay_path.data(), m_replay_path.size());
  ImGui::PopItemWidth();
  if (ImGui::Button("Replay path (p)")) replay_path();
  ImGui::SameLine();
  if (ImGui::Button("Connect device (u)")) connect_device();
  if (m_drill && running) {
    if (const auto* bridge = dynamic_cast<const drill::UdpBridge*>(m_drill->source()))
      ImGui::Text("device bridge on 127.0.0.1:%u: %llu packets (%llu rejected)", unsigned(bridge->port()),
                  static_cast<unsigned long long>(bridge->received_packets()),
                  static_cast<unsigned long long>(bridge->rejected_packets()));
    else if (const auto* path = dynamic_cast<const drill::ScriptedTrajectory*>(m_drill->source()))
      ImGui::Text("replaying %.2f s of path", path->duration());
  }
  ImGui::Separator();
  ImGui::Text("burr (%.1f, %.1f, %.1f) mm, radius %.1f mm", m_tool_mm.x(), m_tool_mm.y(), m_tool_mm.z(),
              m_options.burr_radius_mm);
  if (m_options.shaft_radius_mm > 0) ImGui::Text("shaft radius %.2f mm", m_options.shaft_radius_mm);
  float tilt = float(m_tool_tilt_deg), azimuth = float(m_tool_azimuth_deg);
  const bool tilted = ImGui::SliderFloat("tilt (i, k)", &tilt, 0.0f, 180.0f, "%.0f deg");
  const bool turned = ImGui::SliderFloat("turn (j, l)", &azimuth, -180.0f, 180.0f, "%.0f deg");
  if (tilted || turned) turn_tool(double(tilt) - m_tool_tilt_deg, double(azimuth) - m_tool_azimuth_deg);
  if (!m_drill) return;
  const DrillFigures& f = m_figures;
  ImGui::Separator();
  ImGui::Text("session %.2f s, %zu haptic ticks", f.session_s, f.ticks);
  ImGui::Text("force %.3f N (%.2f, %.2f, %.2f) %s", f.force_n.norm(), f.force_n.x(), f.force_n.y(), f.force_n.z(),
              f.contact ? "CONTACT" : "free");
  ImGui::Text("haptic period p50 %.3f  p99 %.3f  p99.9 %.3f ms", f.haptic_period_ms.p50, f.haptic_period_ms.p99,
              f.haptic_period_ms.p999);
  ImGui::Text("collision update p50 %.3f  p99 %.3f ms (%zu updates)", f.update_time_ms.p50, f.update_time_ms.p99,
              f.update_time_ms.count);
  ImGui::Text("removed %.2f mm3 so far", f.removed_volume_mm3);
  if (m_drill_surface)
    ImGui::Text("surface at %.2f s: %.2f mm3 less inside", m_drill_surface->t_s,
                m_drill->initial_volume_mm3() - m_drill_surface->volume_mm3);
  if (m_drill_reported) ImGui::TextWrapped("%s", m_drill_summary.c_str());
}

void Workbench::update_deform() {
  auto s = m_deform->latest();
  if (!s) return;
  const bool fresh = s != m_deform_state;
  if (fresh) {
    m_deform_state = std::move(s);
    // The panel's parameter fields show the values in use once they change (or a change is refused).
    if (m_deform_state->parameters != m_parameter_seen || m_deform_state->parameter_error != m_parameter_error_seen) {
      m_parameter_seen = m_deform_state->parameters;
      m_parameter_error_seen = m_deform_state->parameter_error;
      m_parameter_edit = m_parameter_seen;
    }
    if (m_logged_particle >= 0 && std::size_t(m_logged_particle) < m_deform_state->positions_mm.size()) {
      const Vec3& p = m_deform_state->positions_mm[std::size_t(m_logged_particle)];
      m_deform_log.push_back({{"frame", m_frame},
                              {"t_s", m_deform_state->time_s},
                              {"steps", m_deform_state->steps},
                              {"integrator", m_deform_state->integrator},
                              {"grabbed", m_grab.active},
                              {"position_mm", {p.x(), p.y(), p.z()}},
                              {"momentum_kg_mm_s",
                               {m_deform_state->linear_momentum.x(), m_deform_state->linear_momentum.y(),
                                m_deform_state->linear_momentum.z()}}});
    }
  }
  if (!fresh && !m_field_dirty) return;
  m_field_dirty = false;
  const DeformState& st = *m_deform_state;
  // The bodies' boundary with a value per vertex: displacement at the vertex, or the average of
  // the stress or strain of the tetrahedra whose boundary faces meet there.
  geometry::TriangleMesh mesh;
  mesh.vertices = st.positions_mm;
  std::vector<double> value(mesh.vertices.size(), 0.0), weight(mesh.vertices.size(), 0.0);
  for (std::size_t b = 0; b < m_body_surfaces.size(); ++b) {
    const BodySurface& bs = m_body_surfaces[b];
    const std::vector<double>* cell = m_field == DeformField::VonMises ? &st.von_mises_pa[b]
                                      : m_field == DeformField::Strain ? &st.equivalent_strain[b]
                                                                       : nullptr;
    for (std::size_t f = 0; f < bs.faces.size(); ++f) {
      mesh.triangles.push_back(bs.faces[f]);
      for (std::int32_t vi : bs.faces[f]) {
        const auto v = std::size_t(vi);
        if (cell == nullptr) {
          value[v] = (st.positions_mm[v] - m_rest_positions[v]).norm();
          weight[v] = 1.0;
        } else if (std::size_t(bs.face_tet[f]) < cell->size()) {
          value[v] += (*cell)[std::size_t(bs.face_tet[f])] * (m_field == DeformField::VonMises ? 1e-3 : 1.0);  // Pa → kPa
          weight[v] += 1.0;
        }
      }
    }
  }
  double lo = INFINITY, hi = -INFINITY;
  for (std::size_t v = 0; v < value.size(); ++v)
    if (weight[v] > 0) {
      value[v] /= weight[v];
      lo = std::min(lo, value[v]);
      hi = std::max(hi, value[v]);
    }
  if (!(lo <= hi)) lo = hi = 0.0;
  if (m_field == DeformField::Displacement || lo >= 0) lo = 0.0;  // magnitudes start at zero
  if (hi - lo < 1e-12) hi = lo + 1e-12;
  m_field_range = {lo, hi};
  std::vector<Vec3> colours(value.size());
  for (std::size_t v = 0; v < value.size(); ++v)
    colours[v] = viz::colormap_rgb(viz::Colormap::Viridis, (value[v] - lo) / (hi - lo));
  m_deform_gpu->upload_coloured(mesh, colours);
  m_grab_lines->clear();
  if (m_grab.active && std::size_t(m_grab.particle) < st.positions_mm.size())
    m_grab_lines->add(st.positions_mm[std::size_t(m_grab.particle)], m_grab.target_mm, kCrosshairColour);
  m_grab_lines->upload();
}

void Workbench::grab(double x_px, double y_px) {
  m_grab.active = false;
  if (!m_deform_state) return;
  const auto [origin, dir] = m_camera.pick_ray(x_px - m_rect_3d.x, y_px - m_rect_3d.y, m_rect_3d.width, m_rect_3d.height);
  const viz::Camera cam = m_camera.camera();
  double best = INFINITY;
  std::int32_t best_particle = -1;
  for (const BodySurface& bs : m_body_surfaces)
    for (const Tri& f : bs.faces)
      for (std::int32_t vi : f) {
        const Vec3& p = m_deform_state->positions_mm[std::size_t(vi)];
        const double along = (p - origin).dot(dir);
        if (along <= 0) continue;
        // Distance from the ray in pixels at the point's depth.
        const double mm_per_px = 2.0 * along * std::tan(0.5 * cam.fov_y_deg * kPi / 180.0) / std::max(1.0, m_rect_3d.height);
        const double px = (p - origin - along * dir).norm() / mm_per_px;
        const double score = px + 1e-3 * along;  // nearer the cursor, then nearer the eye
        if (px < 12.0 && score < best) {
          best = score;
          best_particle = vi;
        }
      }
  if (best_particle < 0) return;
  m_grab = {true, best_particle, m_deform_state->positions_mm[std::size_t(best_particle)], m_grab_stiffness_n_per_mm};
  m_logged_particle = best_particle;
  m_deform->set_grab(m_grab);
}

void Workbench::colour_bar() {
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const float x0 = float(m_view_area.x + m_view_area.width - 100), x1 = x0 + 22;
  const float y0 = float(m_rect_3d.y + 60), y1 = float(m_rect_3d.y + m_rect_3d.height - 60);
  constexpr int kSteps = 64;
  for (int i = 0; i < kSteps; ++i) {
    const double ta = 1.0 - double(i) / kSteps, tb = 1.0 - double(i + 1) / kSteps;  // top = maximum
    const Vec3 ca = viz::colormap_rgb(viz::Colormap::Viridis, ta), cb = viz::colormap_rgb(viz::Colormap::Viridis, tb);
    const ImU32 ua = IM_COL32(int(255 * ca.x()), int(255 * ca.y()), int(255 * ca.z()), 255);
    const ImU32 ub = IM_COL32(int(255 * cb.x()), int(255 * cb.y()), int(255 * cb.z()), 255);
    const float ya = y0 + (y1 - y0) * float(i) / kSteps, yb = y0 + (y1 - y0) * float(i + 1) / kSteps;
    dl->AddRectFilledMultiColor(ImVec2(x0, ya), ImVec2(x1, yb), ua, ua, ub, ub);
  }
  const ImU32 white = IM_COL32(230, 230, 230, 255);
  dl->AddRect(ImVec2(x0, y0), ImVec2(x1, y1), white);
  const std::size_t f = static_cast<std::size_t>(m_field);
  const std::string title = fmt::format("{} ({})", kDeformFieldNames[f], kDeformFieldUnits[f]);
  dl->AddText(ImVec2(std::min(x0, float(m_view_area.x + m_view_area.width) - ImGui::CalcTextSize(title.c_str()).x - 6), y0 - 36),
              white, title.c_str());
  for (int i = 0; i <= 4; ++i) {
    const double t = 1.0 - i / 4.0;
    const double value = m_field_range[0] + t * (m_field_range[1] - m_field_range[0]);
    const float y = y0 + (y1 - y0) * float(i) / 4.0f;
    dl->AddLine(ImVec2(x1, y), ImVec2(x1 + 4, y), white);
    dl->AddText(ImVec2(x1 + 6, y - 7), white, fmt::format("{:.3g}", value).c_str());
  }
}

void Workbench::deform_panel() {
  ImGui::TextWrapped("left drag on a body: pull it (a spring to the cursor); right drag: turn; space: run / pause");
  const bool run = m_deform->running();
  if (ImGui::Button(run ? "Pause (space)" : "Run (space)")) m_deform->set_running(!run);
  ImGui::SameLine();
  if (ImGui::Button("Step (n)")) m_deform->step_once();
  if (!m_deform_state) return;
  const DeformState& st = *m_deform_state;
  const auto& names = m_deform->integrators();
  int current = int(std::find(names.begin(), names.end(), st.integrator) - names.begin());
  std::vector<const char*> items;
  for (const auto& n : names) items.push_back(n.c_str());
  if (ImGui::Combo("integrator (i)", &current, items.data(), int(items.size())) && current < int(names.size()))
    m_deform->set_integrator(names[std::size_t(current)]);
  int field = static_cast<int>(m_field);
  if (ImGui::Combo("colour (m)", &field, kDeformFieldNames.data(), 3)) {
    m_field = static_cast<DeformField>(field);
    m_field_dirty = true;
  }
  float k = float(m_grab_stiffness_n_per_mm);
  if (ImGui::DragFloat("pull spring (N/mm)", &k, 0.005f, 1e-4f, 100.0f, "%.4f")) m_grab_stiffness_n_per_mm = k;
  if (m_grab.active)
    ImGui::Text("pulling with %.4g N/mm%s", st.grab_stiffness_n_per_mm,
                st.grab_stiffness_n_per_mm < m_grab.stiffness_n_per_mm ? " (capped for stability)" : "");
  ImGui::Text("t = %.4f s, %lld steps of %.4g s", st.time_s, static_cast<long long>(st.steps), m_deform->dt_s());
  if (!st.error.empty()) ImGui::TextWrapped("stopped: %s", st.error.c_str());
  if (!st.history.empty()) energy_plots(st);
  parameter_panel(st);
}

void Workbench::energy_plots(const DeformState& st) {
  const EnergySample& last = st.history.back();
  ImGui::Text("energy (mJ): kinetic %.4g, elastic %.4g, total %.4g", last.kinetic_mj, last.elastic_mj, last.total_mj);
  auto plot = [&](const char* label, double EnergySample::*member, const char* unit) {
    std::vector<float> y;
    for (const EnergySample& e : st.history) y.push_back(float(e.*member));
    const std::string overlay = fmt::format("{} {:.4g} {}", label, st.history.back().*member, unit);
    ImGui::PlotLines(fmt::format("##{}", label).c_str(), y.data(), int(y.size()), 0, overlay.c_str(), FLT_MAX, FLT_MAX,
                     ImVec2(ImGui::GetContentRegionAvail().x, 60));
  };
  plot("kinetic", &EnergySample::kinetic_mj, "mJ");
  plot("elastic", &EnergySample::elastic_mj, "mJ");
  plot("total", &EnergySample::total_mj, "mJ");
  plot("step time", &EnergySample::step_ms, "ms");
}

void Workbench::parameter_panel(const DeformState& st) {
  const auto& params = m_deform->parameters();
  if (params.empty() || m_parameter_edit.size() != params.size()) return;
  if (m_focus_parameter >= 0) ImGui::SetNextItemOpen(true);
  if (ImGui::CollapsingHeader("model parameters", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::TextWrapped("enter applies a value between two steps; e: edit the first");
    bool apply = false;
    ImGui::PushItemWidth(-1);
    for (std::size_t i = 0; i < params.size(); ++i) {
      ImGui::TextUnformatted(params[i].label.c_str());
      if (m_focus_parameter == int(i)) {
        ImGui::SetKeyboardFocusHere();
        m_focus_parameter = -1;
      }
      ImGui::PushID(int(i));
      apply |= ImGui::InputDouble("##parameter", &m_parameter_edit[i], 0.0, 0.0, "%.6g",
                                  ImGuiInputTextFlags_EnterReturnsTrue | ImGuiInputTextFlags_CharsScientific |
                                      ImGuiInputTextFlags_AutoSelectAll);
      ImGui::PopID();
    }
    ImGui::PopItemWidth();
    if (apply) m_deform->set_parameters(m_parameter_edit);
    if (!st.parameter_error.empty()) ImGui::TextWrapped("refused: %s", st.parameter_error.c_str());
    if (!st.changes.empty())
      ImGui::Text("%zu changes, the last before step %lld", st.changes.size(),
                  static_cast<long long>(st.changes.back().step + 1));
  }
}

void Workbench::write_deform_log() {
  if (m_options.deform_log.empty() || !m_deform) return;
  nlohmann::json rest = nullptr;
  if (m_logged_particle >= 0 && std::size_t(m_logged_particle) < m_rest_positions.size()) {
    const Vec3& r = m_rest_positions[std::size_t(m_logged_particle)];
    rest = {r.x(), r.y(), r.z()};
  }
  nlohmann::json parameters = nlohmann::json::array(), changes = nlohmann::json::array(), final = nullptr;
  const auto& params = m_deform->parameters();
  for (std::size_t i = 0; i < params.size(); ++i)
    parameters.push_back({{"pointer", params[i].pointer},
                          {"label", params[i].label},
                          {"file_value", params[i].value},
                          {"value", m_deform_state && i < m_deform_state->parameters.size() ? m_deform_state->parameters[i]
                                                                                              : params[i].value}});
  if (m_deform_state) {
    for (const ParameterChange& c : m_deform_state->changes)
      changes.push_back({{"step", c.step}, {"pointer", c.pointer}, {"value", c.value}});
    nlohmann::json positions = nlohmann::json::array();
    for (const Vec3& p : m_deform_state->positions_mm) positions.push_back({p.x(), p.y(), p.z()});
    final = {{"steps", m_deform_state->steps}, {"t_s", m_deform_state->time_s}, {"integrator", m_deform_state->integrator},
             {"positions_mm", positions}};
  }
  const nlohmann::json j = {{"particle", m_logged_particle}, {"rest_mm", rest},        {"samples", m_deform_log},
                            {"parameters", parameters},     {"changes", changes},     {"final", final}};
  const std::string text = j.dump(1) + "\n";
  write_file_atomically(m_options.deform_log, [&](std::ostream& out) { out << text; }, false);
}

void Workbench::legend(const std::vector<std::pair<std::string, Vec3>>& entries) {
  if (entries.size() < 2) return;
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const float line = ImGui::GetTextLineHeight() + 4.0f, swatch = 12.0f;
  float text_w = 0.0f;
  for (const auto& [name, colour] : entries) text_w = std::max(text_w, ImGui::CalcTextSize(name.c_str()).x);
  text_w = std::min(text_w, float(0.5 * m_rect_3d.width));  // long names are cut at the box
  const float x1 = float(m_rect_3d.x + m_rect_3d.width) - 8.0f, x0 = x1 - (text_w + swatch + 18.0f);
  const float y0 = float(m_rect_3d.y) + 48.0f, y1 = y0 + float(entries.size()) * line + 6.0f;
  dl->AddRectFilled(ImVec2(x0, y0), ImVec2(x1, y1), IM_COL32(18, 18, 22, 230));
  dl->AddRect(ImVec2(x0, y0), ImVec2(x1, y1), IM_COL32(140, 140, 140, 255));
  dl->PushClipRect(ImVec2(x0, y0), ImVec2(x1 - 4.0f, y1), true);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const Vec3& c = entries[i].second;
    const float y = y0 + 4.0f + float(i) * line;
    dl->AddRectFilled(ImVec2(x0 + 6.0f, y + 1.0f), ImVec2(x0 + 6.0f + swatch, y + 1.0f + swatch),
                      IM_COL32(int(255 * c.x()), int(255 * c.y()), int(255 * c.z()), 255));
    dl->AddText(ImVec2(x0 + swatch + 12.0f, y), IM_COL32(230, 230, 230, 255), entries[i].first.c_str());
  }
  dl->PopClipRect();
}

void Workbench::body_legend() {
  if (m_body_surfaces.size() < 2 || !m_deform_state) return;
  std::vector<std::pair<std::string, Vec3>> entries;
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const viz::Camera cam = m_camera.camera();
  const Mat4 mvp = cam.projection_matrix(m_rect_3d.width / std::max(1.0, m_rect_3d.height)) * cam.view_matrix();
  for (std::size_t b = 0; b < m_body_surfaces.size(); ++b) {
    const Vec3& colour = kBodyMarkers[b % kBodyMarkers.size()];
    entries.emplace_back(fmt::format("{}  {}", b + 1, m_body_names[b]), colour);
    // The body's number on its boundary's centre as the camera sees it now.
    Vec3 centre = Vec3::Zero();
    std::size_t n = 0;
    for (const Tri& f : m_body_surfaces[b].faces)
      for (std::int32_t vi : f) {
        centre += m_deform_state->positions_mm[std::size_t(vi)];
        ++n;
      }
    if (n == 0) continue;
    const Vec4 clip = mvp * Vec4(centre.x() / double(n), centre.y() / double(n), centre.z() / double(n), 1.0);
    if (clip.w() <= 0) continue;
    const float x = float(m_rect_3d.x + (clip.x() / clip.w() + 1.0) / 2.0 * m_rect_3d.width);
    const float y = float(m_rect_3d.y + (1.0 - clip.y() / clip.w()) / 2.0 * m_rect_3d.height);
    const std::string label = std::to_string(b + 1);
    const ImVec2 size = ImGui::CalcTextSize(label.c_str());
    const ImU32 col = IM_COL32(int(255 * colour.x()), int(255 * colour.y()), int(255 * colour.z()), 255);
    dl->AddRectFilled(ImVec2(x - size.x / 2 - 4, y - size.y / 2 - 2), ImVec2(x + size.x / 2 + 4, y + size.y / 2 + 2), col, 3.0f);
    dl->AddText(ImVec2(x - size.x / 2, y - size.y / 2), IM_COL32(0, 0, 0, 255), label.c_str());
  }
  legend(entries);
}

void Workbench::overlays() {
  if (m_workspace == Workspace::Deform && m_deform) {
    colour_bar();
    body_legend();
  }
  if (m_workspace == Workspace::Scene || m_workspace == Workspace::Segment) {  // what the 3-D view shows, by colour
    std::vector<std::pair<std::string, Vec3>> entries;
    for (const auto& o : m_objects)
      if (o.visible) entries.emplace_back(o.name, o.colour);
    if (m_workspace == Workspace::Segment && m_state && !m_state->surface.triangles.empty() && !entries.empty())
      entries.emplace_back("balloon", kBalloonColour);
    legend(entries);
  }
  ImDrawList* dl = ImGui::GetForegroundDrawList();
  const ImU32 white = IM_COL32(230, 230, 230, 255);
  if (m_window)  // a snapshot has no mouse
    dl->AddText(ImVec2(float(m_rect_3d.x + 6), float(m_rect_3d.y + 4)), white, "3-D  (drag: turn, right-drag: move, wheel: zoom)");
  for (int a = 0; a < 3; ++a) {
    const auto& v = m_slice_views[std::size_t(a)];
    if (!v) continue;
    const std::string label = fmt::format("{} {} = {} / {}", kAxisNames[std::size_t(a)], kIndexNames[std::size_t(a)],
                                          m_slice[std::size_t(a)], m_ct->size(a) - 1);
    dl->AddText(ImVec2(float(v->rect().x + 6), float(v->rect().y + 4)), white, label.c_str());
  }
}

/// Viewport and scissor on the window rectangle @p r (points, y down) of a framebuffer
/// @p fb_height pixels high with @p fb_scale pixels per point (GL counts y up).
void clip_to(const PixelRect& r, double fb_scale, int fb_height) {
  const auto x = GLint(r.x * fb_scale), y = GLint(fb_height - (r.y + r.height) * fb_scale);
  const auto w = GLsizei(r.width * fb_scale), h = GLsizei(r.height * fb_scale);
  glViewport(x, y, w, h);
  glScissor(x, y, w, h);
}

void Workbench::draw_slice_view(int axis, double fb_scale, int fb_height) {
  const SliceView& v = *m_slice_views[std::size_t(axis)];
  const PixelRect& r = v.rect();
  clip_to(r, fb_scale, fb_height);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_DEPTH_TEST);
  const gl::Mat4f mvp = to_float(v.ndc_from_index());
  m_painter->draw_slice(*m_slice_2d[std::size_t(axis)], mvp, m_window_width, m_level);
  m_painter->draw_lines(*m_contours[std::size_t(axis)], mvp);
  m_painter->draw_lines(*m_marks[std::size_t(axis)], mvp);
}

void Workbench::draw_3d(const PixelRect& r, double fb_scale, int fb_height) {
  clip_to(r, fb_scale, fb_height);
  render_3d(r);
}

std::vector<double> Workbench::view_key(int w_px, int h_px) const {
  const viz::Camera cam = m_camera.camera();
  const Mat4 view = cam.view_matrix(), projection = cam.projection_matrix(m_rect_3d.width / std::max(1.0, m_rect_3d.height));
  std::vector<double> key = {double(static_cast<int>(m_workspace)), double(w_px), double(h_px),
                             double(gl::upload_count()), m_window_width, m_level, double(m_mesh_source),
                             m_mesh ? 1.0 : 0.0, double(m_objects.size()), m_camera_moving ? 1.0 : 0.0};
  key.insert(key.end(), view.data(), view.data() + 16);
  key.insert(key.end(), projection.data(), projection.data() + 16);
  for (const auto& o : m_objects) key.push_back(o.visible ? 1.0 : 0.0);
  if (m_workspace == Workspace::Mesh && m_mesh) {
    const viz::ClipPlane p = clip_plane();
    key.insert(key.end(), {p.normal.x(), p.normal.y(), p.normal.z(), p.point.x(), p.point.y(), p.point.z()});
  }
  return key;
}

void Workbench::draw_3d_cached(const PixelRect& r, double fb_scale, int fb_height) {
  clip_to(r, fb_scale, fb_height);  // the view's pixels in the target framebuffer
  GLint target[4] = {0, 0, 0, 0};
  glGetIntegerv(GL_VIEWPORT, target);
  const int w = target[2], h = target[3];
  if (w <= 0 || h <= 0) return;
  if (!m_cache_fbo) {
    glGenFramebuffers(1, &m_cache_fbo);
    glGenRenderbuffers(1, &m_cache_colour);
    glGenRenderbuffers(1, &m_cache_depth);
  }
  const GLuint shown = m_fbo;  // the window's framebuffer (0) or the snapshot's
  if (w != m_cache_w || h != m_cache_h) {
    glBindRenderbuffer(GL_RENDERBUFFER, m_cache_colour);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindRenderbuffer(GL_RENDERBUFFER, m_cache_depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, m_cache_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, m_cache_colour);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, m_cache_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, shown);
    m_cache_w = w;
    m_cache_h = h;
    m_cache_key.clear();
  }
  std::vector<double> key = view_key(w, h);
  if (key != m_cache_key) {
    glBindFramebuffer(GL_FRAMEBUFFER, m_cache_fbo);
    glViewport(0, 0, w, h);
    glScissor(0, 0, w, h);
    render_3d(r);
    glBindFramebuffer(GL_FRAMEBUFFER, shown);
    clip_to(r, fb_scale, fb_height);
    m_cache_key = std::move(key);
    ++m_cache_draws;
  }
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m_cache_fbo);
  glBlitFramebuffer(0, 0, w, h, target[0], target[1], target[0] + w, target[1] + h, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, shown);
}

void Workbench::render_3d(const PixelRect& r) {
  glClearColor(0.12f, 0.13f, 0.16f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  const viz::Camera cam = m_camera.camera();
  const Mat4 view = cam.view_matrix();
  const gl::Mat4f mvp = to_float(cam.projection_matrix(r.width / std::max(1.0, r.height)) * view);
  const gl::Mat4f v = to_float(view);
  if (m_workspace == Workspace::Deform) {
    m_painter->draw_mesh(*m_deform_gpu, mvp, v);
    glDisable(GL_DEPTH_TEST);
    m_painter->draw_lines(*m_grab_lines, mvp);
    return;
  }
  if (m_workspace == Workspace::Drill) {
    if (m_drill_surface) {
      m_painter->draw_mesh(*m_drill_gpu, mvp, v);
    } else if (const auto material = drill_material()) {
      if (m_drill_gpu->vertex_count() == 0) m_drill_gpu->upload(geometry::tet_boundary(*material), kMaterialColour, /*flat=*/true);
      m_painter->draw_mesh(*m_drill_gpu, mvp, v);
    }
    m_painter->draw_mesh(*m_tool_gpu, mvp, v);
    glDisable(GL_DEPTH_TEST);
    m_painter->draw_lines(*m_force_lines, mvp);
    return;
  }
  if (m_workspace == Workspace::Mesh) {
    if (m_mesh) {
      const viz::ClipPlane p = clip_plane();
      const Eigen::Vector4f clip(float(-p.normal.x()), float(-p.normal.y()), float(-p.normal.z()),
                                 float(p.normal.dot(p.point)));
      m_painter->draw_mesh(*m_tet_gpu, mvp, v, clip);
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(1.0f, 1.0f);  // the section's edges are drawn on its faces
      m_painter->draw_mesh(*m_section_gpu, mvp, v);
      glDisable(GL_POLYGON_OFFSET_FILL);
      m_painter->draw_lines(*m_section_lines, mvp);
    } else if (m_mesh_source >= 0 && m_mesh_source < int(m_objects.size())) {
      m_painter->draw_mesh(*m_objects[std::size_t(m_mesh_source)].gpu, mvp, v);
    }
    glDisable(GL_DEPTH_TEST);
    return;
  }
  for (const auto& o : m_objects)
    if (o.visible)
      m_painter->draw_mesh(m_camera_moving && o.coarse ? *o.coarse : *o.gpu, mvp, v, Eigen::Vector4f(0, 0, 0, 1), o.cull_back);
  if (m_workspace == Workspace::Segment && m_ct) {
    m_painter->draw_mesh(*m_balloon_gpu, mvp, v);
    for (int a = 0; a < 3; ++a) m_painter->draw_slice(*m_slice_3d[std::size_t(a)], mvp, m_window_width, m_level);
    glDisable(GL_DEPTH_TEST);
    m_painter->draw_lines(*m_marks_3d, mvp);
  }
  glDisable(GL_DEPTH_TEST);
}

void Workbench::draw(int fb_width, int fb_height) {
  int win_w = 0, win_h = 0, unused_w = 0, unused_h = 0;
  surface_size(win_w, win_h, unused_w, unused_h);
  const double scale = win_w > 0 ? double(fb_width) / win_w : 1.0;
  glEnable(GL_SCISSOR_TEST);
  glViewport(0, 0, fb_width, fb_height);
  glScissor(0, 0, fb_width, fb_height);
  glClearColor(0.08f, 0.08f, 0.09f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  // The camera moves while a turn or move drag is held, or when it changed since the last
  // frame (the wheel): large surfaces are then drawn coarse (kCoarseAbove).
  const Mat4 view = m_camera.camera().view_matrix();
  m_camera_moving = m_drag == Drag::Rotate || m_drag == Drag::Pan || (m_last_view && *m_last_view != view);
  m_last_view = view;
  if (m_workspace == Workspace::Drill || m_workspace == Workspace::Deform)  // they change every frame
    draw_3d(m_rect_3d, scale, fb_height);
  else
    draw_3d_cached(m_rect_3d, scale, fb_height);
  for (int a = 0; a < 3; ++a)
    if (m_slice_views[std::size_t(a)]) draw_slice_view(a, scale, fb_height);
  glDisable(GL_SCISSOR_TEST);
  glViewport(0, 0, fb_width, fb_height);
}

void Workbench::snapshot() {
  // Work started at open (the seeds' balloon) finishes first, so the picture shows its result.
  const Clock::time_point t0 = Clock::now();
  while (m_session && m_session->busy()) {
    if (Clock::now() - t0 > std::chrono::minutes(10)) throw Error("--snapshot: the balloon did not finish in 10 minutes");
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ImGuiIO& io = ImGui::GetIO();
  const int w = m_options.width_px, h = m_options.height_px;
  io.DisplaySize = ImVec2(float(w), float(h));
  io.DisplayFramebufferScale = ImVec2(1.0f, 1.0f);
  io.DeltaTime = 1.0f / 60.0f;
  layout(w, h);
  update_from_workers();
  ImGui_ImplOpenGL3_NewFrame();
  ImGui::NewFrame();
  overlays();
  ImGui::Render();
  draw(w, h);
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  glFinish();
  viz::write_png(m_options.snapshot, viz::Image{w, h, gl::read_pixels(w, h)});
  m_stats.frames.push_back({m_workspace, float(std::chrono::duration<double, std::milli>(Clock::now() - t0).count()), false, true});
  if (!m_options.quiet) std::printf("wrote %s\n", m_options.snapshot.string().c_str());
}

void Workbench::run() {
  if (!m_options.snapshot.empty()) {
    snapshot();
    return;
  }
  ImGuiIO& io = ImGui::GetIO();
  for (;;) {
    const Clock::time_point frame_start = Clock::now();
    const std::int64_t cache_draws_before = m_cache_draws;
    glfwPollEvents();
    if (glfwWindowShouldClose(m_window)) break;
    if (m_script && !feed_script()) break;
    int win_w = 0, win_h = 0, fb_w = 0, fb_h = 0;
    surface_size(win_w, win_h, fb_w, fb_h);
    io.DisplaySize = ImVec2(float(win_w), float(win_h));
    if (win_w > 0) io.DisplayFramebufferScale = ImVec2(float(fb_w) / float(win_w), float(fb_h) / float(win_h));
    const Clock::time_point now = Clock::now();
    const double dt = std::chrono::duration<double>(now - m_last_frame).count();
    m_last_frame = now;
    io.DeltaTime = m_script ? 1.0f / 60.0f : float(std::clamp(dt, 1e-4, 0.5));  // a replay is frame-exact
    if (m_frame > 0) {
      m_frame_ms.push_back(1e3 * dt);
      if (m_frame_ms.size() > 120) m_frame_ms.erase(m_frame_ms.begin());
    }
    layout(win_w, win_h);
    apply_input();
    update_from_workers();
    layout(win_w, win_h);  // the workspace may have changed
    ImGui_ImplOpenGL3_NewFrame();
    ImGui::NewFrame();
    panel();
    overlays();
    ImGui::Render();
    m_capture_mouse = io.WantCaptureMouse;
    m_capture_keyboard = io.WantCaptureKeyboard;
    draw(fb_w, fb_h);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    for (const std::string& name : m_pending_screenshots) {
      viz::Image img{fb_w, fb_h, gl::read_pixels(fb_w, fb_h)};
      viz::write_png(m_options.screenshots / name, img);
    }
    m_pending_screenshots.clear();
    glfwSwapBuffers(m_window);
    ++m_frame;
    if (!m_wait_start) ++m_script_frame;
    const bool waiting = m_wait_start.has_value();
    // While a script waits for a worker, leave it the processor (this machine may have two).
    if (waiting) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    // While drilling, at most 60 frames a second (a display's rate), so the frame loop and the
    // software rasteriser do not take the collision thread's processor.
    if (drilling()) std::this_thread::sleep_until(frame_start + std::chrono::microseconds(16667));
    m_stats.frames.push_back({m_workspace, float(std::chrono::duration<double, std::milli>(Clock::now() - frame_start).count()),
                              waiting, m_cache_draws != cache_draws_before || m_workspace == Workspace::Drill ||
                                           m_workspace == Workspace::Deform});
    if (m_options.max_frames > 0 && m_frame >= m_options.max_frames) break;
  }
  write_deform_log();
  if (!m_options.record.empty()) {
    EventScript script;
    script.window_width_px = m_options.width_px;
    script.window_height_px = m_options.height_px;
    glfwGetWindowSize(m_window, &script.window_width_px, &script.window_height_px);
    script.events = m_recorded;
    script.save(m_options.record);
    if (!m_options.quiet)
      std::printf("%zu events recorded to %s\n", m_recorded.size(), m_options.record.string().c_str());
  }
}

}  // namespace

const char* workspace_name(Workspace workspace) noexcept {
  switch (workspace) {
    case Workspace::Segment: return "segment";
    case Workspace::Scene: return "scene";
    case Workspace::Mesh: return "mesh";
    case Workspace::Drill: return "drill";
    case Workspace::Deform: return "deform";
  }
  return "?";
}

WorkbenchStats run_workbench(const WorkbenchOptions& options) {
  Workbench bench(options);
  bench.run();
  return bench.take_stats();
}

}  // namespace ido::view
