// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "ubersim/scene.hpp"
#include "physics/contact_island.hpp"
#include "physics/ode_handles.hpp"
#include "physics/scene_graph.hpp"

namespace ubersim::kernel {

/// How candidate pairs are found before ODE's narrow phase.
enum class Broadphase {
  kSceneGraph,     ///< hierarchical bounding spheres over the scene graph (the paper's method)
  kHash,           ///< ODE's multi-resolution hash space
  kSweepAndPrune,  ///< ODE's sweep-and-prune space
  kField,          ///< the kernel's own for a field: each robot (each loose body) as one box swept along x, against the static field
};

/// Parses "scene_graph", "hash", "sap" or "field"; throws std::invalid_argument otherwise.
Broadphase ParseBroadphase(const std::string& name);

/// How many contact points ODE may report for one pair before they are thinned to the world's
/// max_contacts. (Asking ODE for max_contacts alone gives its first-found points: a chassis
/// pushed against a wall then jitters at 6 cm/s, and measured no faster.)
inline constexpr int kContactCandidates = 64;
/// Contacts two robot shells (or a shell and a wall) always get, whatever max_contacts says: two
/// levels, two per level for flat faces pressed together (CollideUprightPrisms).
inline constexpr int kShellContacts = 4;
/// Deepest contact between two shells that gets the robot contact ERP (SetRobotContactErp), m:
/// robots pushing or crashing meet within this; deeper, they were put into each other.
inline constexpr double kStiffRobotContactDepth = 0.03;
/// How fast two shells inside each other are parted at most, m/s: a teleport's overlap is undone
/// over a few steps, not in one blow at the world's correcting velocity (3 m/s), which tipped
/// wheel robots over at the fast profile's 5 ms. Pushes and crashes sink a few millimetres at
/// most, which ERP undoes slower than this.
inline constexpr double kRobotPartingSpeed = 1.0;

/// Thins the first `found` contacts to at most `keep`: the deepest, then each time the one
/// farthest from those kept (ODE reports points in the order it finds them, often along one
/// edge). Returns how many remain at the front of `contacts`.
int SpreadContacts(std::vector<dContactGeom>& contacts, int found, int keep);

/// The contact of a sphere and a plane, `first` and `second` in either order: bit for bit what
/// dCollide(first, second) gives, without its dispatch. Returns 1 when they touch, else 0.
int CollideSphereAndPlane(dGeomID first, dGeomID second, dContactGeom& contact);
/// The model-file name of a broadphase.
const char* ToString(Broadphase b);

/// Contact parameters by pair of material names, with a rule for pairs not in the table.
class MaterialTable {
 public:
  /// Sets the surface used when materials `a` and `b` touch (either order).
  void SetPair(const std::string& a, const std::string& b, const SurfaceMaterial& surface);
  /// Counts SetPair calls (surfaces resolved before a change are stale after it).
  std::uint64_t version() const { return version_; }
  /// The surface for two touching materials: the table entry when there is one, else the
  /// combination: mu and mu2 geometric means, bounce and bounce velocity the larger, ERP the
  /// smaller and CFM the larger of those set, rolling friction and slip the larger.
  SurfaceMaterial Resolve(const SurfaceMaterial& a, const SurfaceMaterial& b) const;
  /// Number of explicit pairs.
  std::size_t size() const { return pairs_.size(); }

 private:
  // Compares (name, name) pairs of strings or string views alike, so a lookup copies no string
  // (it runs for every touching pair of every step).
  struct NamePairLess {
    using is_transparent = void;
    template <class A, class B>
    bool operator()(const A& x, const B& y) const {
      const std::string_view x1 = x.first, x2 = x.second, y1 = y.first, y2 = y.second;
      return x1 < y1 || (x1 == y1 && x2 < y2);
    }
  };
  std::map<std::pair<std::string, std::string>, SurfaceMaterial, NamePairLess> pairs_;
  std::uint64_t version_ = 0;
};

/// Counters of the last Collide() call.
struct CollisionStats {
  std::size_t sphere_tests = 0;    ///< bounding-sphere overlap tests (scene-graph broadphase)
  std::size_t narrow_tests = 0;    ///< pairs whose contacts were computed (dCollide or an exact test of our own)
  std::size_t touching_pairs = 0;  ///< pairs with at least one contact
  std::size_t contacts = 0;        ///< contact joints created
  std::size_t swept_contacts = 0;  ///< of those, speculative contacts of fast balls
};

/// Finds colliding geometry pairs over the scene graph and turns contacts into ODE contact joints
/// with parameters from the material table, directional friction and rolling resistance; lets
/// observers see and change each contact first. Never pairs a node with itself, its ancestors
/// or its descendants, two static geometries, or two geometries of one body.
class CollisionManager {
 public:
  /// Files every geometry of `graph` (and later ones) for the chosen broadphase.
  CollisionManager(SceneGraph& graph, Broadphase broadphase, int max_contacts_per_pair);
  ~CollisionManager();
  CollisionManager(const CollisionManager&) = delete;
  CollisionManager& operator=(const CollisionManager&) = delete;

  /// Switches the broadphase (files existing geometries into or out of the ODE space, in the
  /// order they were created).
  void SetBroadphase(Broadphase broadphase);
  /// The broadphase in use.
  Broadphase broadphase() const { return broadphase_; }
  /// The material-pair table.
  MaterialTable& materials() { return materials_; }

  /// Calls `f` for every candidate pair the broadphase yields after the exclusion rules, in a
  /// deterministic order. Bounding spheres are refreshed first.
  void ForEachCandidatePair(const std::function<void(GeomImpl&, GeomImpl&)>& f);
  /// Broadphase + narrow phase: every pair that touches now (no joints are created).
  std::vector<std::pair<GeomImpl*, GeomImpl*>> TouchingPairs();
  /// Broadphase + narrow phase, creating contact joints for the next physics step.
  void Collide();
  /// Turns on the swept test of fast balls for a physics step of `dt` s: a ball that would
  /// travel more than half its radius in one step casts a ray along its velocity, and whatever
  /// it would reach within the step gets a contact now (a speculative contact, at the surface),
  /// so a shot cannot cross a robot's shell or a wall between two steps. 0 turns it off.
  void SetSweptBallStep(double dt) { swept_ball_step_ = dt; }
  /// Turns on speculative contacts between robots for a physics step of `dt` s: two upright
  /// robot shells apart by less than their relative speed covers in a step get their contacts
  /// now, each allowing the approach that closes its gap within the step and no more (ODE's
  /// contact motion along the normal), so a crash meets at the surface instead of a step's
  /// travel (30 mm at 6 m/s and 5 ms) inside. 0 turns it off.
  void SetSweptRobotStep(double dt) { swept_robot_step_ = dt; }
  /// The error reduction of contacts between two robots' shells; < 0: the world's ERP.
  void SetRobotContactErp(double erp) { robot_contact_erp_ = erp; }
  /// The world's step, s, and ERP: shells put into each other are parted at kRobotPartingSpeed.
  void SetStepAndErp(double dt, double erp) {
    step_ = dt;
    erp_ = erp;
  }
  /// The chassis of every two robots whose shells touched (or were about to) in the last
  /// Collide(): their islands are solved with more iterations.
  const std::vector<dBodyID>& RobotsInContact() const { return robots_in_contact_; }
  /// Removes the contact joints of the last step.
  void ClearContacts();
  /// The contacts of this step between a body and the static world: those of a body touching
  /// nothing else are not ODE joints unless made so (StaticContactLog::Join).
  StaticContactLog& StaticContacts() { return static_contacts_; }
  /// Files every geometry anew (SetBroadphase: in creation order) and drops every cache that may
  /// name one: whenever robots come or go. A world built anew from the same robots in the same
  /// order (a snapshot's) then pairs as the original does.
  void Refile();
  /// Counters of the last Collide().
  const CollisionStats& stats() const { return stats_; }
  /// How many pairs' resolved surfaces are cached now (bounded, however long the run).
  std::size_t cached_surfaces() const { return surfaces_.size(); }
  /// Every this many Collide() passes, the surfaces of pairs that have not touched for as many
  /// passes are dropped: the cache holds what touches lately, so memory stays flat all day.
  static constexpr std::uint64_t kSurfaceCacheSweepPasses = 1000;

  /// Where the ball `ball` put at `wanted` overlaps no robot's shell and no static geometry
  /// (walls, goals) by more than `tolerance`, m: `wanted` when it is free, else the nearest
  /// free spot on the level through it (searched in rings of kFreeSpotStep out to `search`, m),
  /// within `bounds` (the largest |x| and |y| its centre may have); none when there is none.
  std::optional<Vec3> FreeBallSpot(const BodyImpl& ball, const Vec3& wanted, double tolerance, double search,
                                   const Eigen::Vector2d& bounds);
  /// The ring spacing of FreeBallSpot's search, m.
  static constexpr double kFreeSpotStep = 0.002;

  /// True when the exclusion rules let a and b collide at all.
  static bool MayCollide(const GeomImpl& a, const GeomImpl& b);
  /// MayCollide while both take part in collisions: the rules that never change for a pair.
  static bool MayEverCollide(const GeomImpl& a, const GeomImpl& b);
  /// Whether a robot's geometry `g` may meet another robot's at all: its shell only
  /// (MayEverCollide's rule; the field broadphase pairs two robots through these alone).
  static bool MeetsOtherRobots(const GeomImpl& g) { return g.hull(); }

 private:
  void Narrow(GeomImpl& a, GeomImpl& b);
  // The contacts of a and b into scratch_ (two upright robot shells by their own test, the rest
  // by ODE's), at most max_contacts_; returns how many.
  int FindContacts(GeomImpl& a, GeomImpl& b);
  // Makes contact joints for the first n contacts in scratch_ (observers, surfaces, friction);
  // with `approach` (one per contact, m/s), speculative ones that let the bodies close at most
  // that fast along the normal.
  void AddContacts(GeomImpl& a, GeomImpl& b, int n, const double* approach = nullptr);
  // The swept test of every fast ball (SetSweptBallStep).
  void SweepFastBalls();
  // One ball at `from` moving at `velocity` relative to `other` against `other`: a contact where
  // its surface would reach it within the step.
  void SweepBallAt(GeomImpl& ball, GeomImpl& other, const Vec3& from, const Vec3& velocity, double radius);
  // The speculative contacts of robots about to meet (SetSweptRobotStep).
  void SweepRobots();
  template <typename F>
  void ForEachPair(F& f);
  // Files a geometry: into the ODE space, or, when it touches planes only, beside it.
  void File(GeomImpl& g);
  // The field broadphase's pairs (Broadphase::kField); its groups are made anew first when
  // geometries came or went.
  template <typename F>
  void ForEachFieldPair(F& f);
  void GroupForField();
  // Takes every geometry out of the ODE spaces and drops the spaces.
  void Unfile();
  // The resolved surface of two touching geometries, cached per pair while neither material
  // nor the table changes (resolving compares and joins names: every contact, every step).
  const SurfaceMaterial& PairSurface(const GeomImpl& a, const GeomImpl& b);

  struct CachedSurface {
    std::uint64_t a_serial, b_serial;  // GeomImpl::serial
    std::uint64_t a_version, b_version, table_version;
    SurfaceMaterial surface;
    std::uint64_t last_pass = 0;  // the Collide() pass that last used it
  };
  // The surface a geometry's last pair used, by the geometry's serial: a wheel meets the carpet
  // step after step, and the memo spares the pair's lookup in surfaces_. Valid for the other
  // geometry of that serial (serials are never reused, addresses are) while `epoch` is
  // surfaces_epoch_ (nothing erased from surfaces_ since).
  struct SurfaceMemo {
    std::uint64_t other_serial = 0;  // 0: none (serials start at 1)
    CachedSurface* cached = nullptr;
    std::uint64_t epoch = 0;
  };
  static constexpr std::uint64_t kMaxMemoSerial = 1 << 16;  // beyond: the lookup alone
  std::vector<SurfaceMemo> surface_memo_;
  std::uint64_t surfaces_epoch_ = 1;

  struct PairHash {
    std::size_t operator()(const std::pair<const GeomImpl*, const GeomImpl*>& p) const {
      return std::hash<const void*>()(p.first) * 31 + std::hash<const void*>()(p.second);
    }
  };

  // A geometry of a field broadphase group, with what its carpet test needs.
  struct FieldGeom {
    GeomImpl* geom;
    const dReal* position;  // its body's (ODE's own arrays: they live as long as the body)
    const dReal* rotation;
    Vec3 centre, half;      // its box in its body's frame, m: a plane needs no world box of it
  };
  // The field broadphase's moving groups: a robot's geometries, or a loose body's. Each step a
  // group's box is the union of its bodies' positions grown by how far each body's geometries
  // reach from it (rigid: measured once, when grouped).
  struct FieldGroup {
    std::vector<FieldGeom> geoms;
    // A robot's group: its shells (indices into geoms), all of it another robot may meet
    // (MeetsOtherRobots). Null robot: a loose body's group.
    const NodeImpl* robot = nullptr;
    std::vector<std::size_t> hulls;
    std::vector<std::pair<dBodyID, double>> bodies;  // body, reach (m)
    struct OnPlane {
      std::size_t plane, geom;  // indices into field_planes_, geoms
      bool covered;             // inside its plane's cover
    };
    std::vector<OnPlane> on_planes;  // the geometries that may meet each plane, plane by plane
    // Per plane, one box in the group's first body's frame around its geometries on that body
    // that are no spheres (a robot's shell and dribbler): a robot standing on its wheels is
    // above the carpet by that one test. Empty (half < 0) when there is none.
    std::vector<FieldGeom> plane_covers;
    std::vector<char> all_covered;  // per plane: every geometry that may meet it is in its cover
    double lo[3], hi[3];                              // this step's box
    bool active = false;                              // any geometry collides
  };
  struct StaticGeom {
    GeomImpl* geom;
    dReal box[6];
  };
  struct FieldPlane {
    GeomImpl* geom;
    Vec3 normal;    // the free side's, unit
    double offset;  // normal·p = offset on the plane, m
  };
  static FieldGeom BoxInBodyFrame(GeomImpl& g);
  void FindStaticsFreeRectangle();  // statics_free_ from field_statics_
  std::vector<FieldGroup> field_groups_;
  std::vector<std::size_t> field_order_;     // field_groups_ by the box's low x (then index)
  std::vector<StaticGeom> field_statics_;    // the field's fixed geometries but planes
  // A rectangle of the carpet plane (x low, x high, y low, y high, m) that no fixed geometry's
  // box enters: a group's box inside it meets none of them (most robots, most steps).
  double statics_free_[4] = {0, -1, 0, -1};
  std::vector<StaticGeom> no_statics_;       // always empty: what a group inside it looks at
  std::vector<FieldPlane> field_planes_;
  std::vector<char> cover_above_;            // per plane, this group's cover wholly above it
  bool field_grouped_ = false;

  SceneGraph& graph_;
  Broadphase broadphase_;
  int max_contacts_;
  MaterialTable materials_;
  CollisionStats stats_;
  OdeSpace space_;        // only for the ODE broadphases
  OdeJointGroup contacts_;
  StaticContactLog static_contacts_;  // makes every contact joint; keeps the static ones it can
  std::vector<dContactGeom> scratch_;
  double swept_ball_step_ = 0.0;
  std::vector<std::pair<const GeomImpl*, const GeomImpl*>> ball_touching_;  // this step's ball pairs
  OdeGeom ray_;           // the swept test's ray, reused
  std::vector<GeomImpl*> balls_;  // the balls, found at the first swept test
  std::vector<GeomImpl*> sweep_targets_;  // what a swept ball may reach: every geometry but planes and shells
  std::vector<GeomImpl*> sweep_shells_;   // robots' shells, swept by the ball's speed relative to them
  std::vector<double> sweep_shell_reach_;  // how far each shell reaches from its body's origin, m
  std::vector<double> sweep_target_reach_; // the same for each target (0 for the static ones)
  // Per target on a body: where the run of targets on that same body (from it on) ends, and the
  // farthest any of them reaches: a robot's parts out of the ball's reach are passed in one test.
  std::vector<std::size_t> sweep_run_end_;
  std::vector<double> sweep_run_reach_;
  bool balls_found_ = false;
  double swept_robot_step_ = 0.0;
  double robot_contact_erp_ = -1.0;
  double step_ = 0.0;  // 0: shells put into each other part at the world's ERP
  double erp_ = 0.2;
  std::vector<GeomImpl*> hulls_;  // the robots' shells, found at the first robot sweep
  // Each shell's motion this step, read once (SweepRobots' pairs grow as the square of the robots).
  struct SweptHull {
    GeomImpl* geom;
    double x, y;         // m
    Vec3 velocity;       // m/s
    double rim_speed;    // |ω_z|·radius, m/s
    double radius;       // m
    double reach_bound;  // radius + (|v| + rim_speed)·dt + slack: no pair reaches farther, m
    double slack;        // how far the shell's origin lies from its body's, m
  };
  std::vector<SweptHull> swept_;
  std::vector<std::size_t> swept_order_;                          // swept_ by x
  // Within reach along x: each pair (i, k), i < k, as one number i·2³² + k, so that sorting
  // numbers sorts the pairs.
  std::vector<std::uint64_t> swept_pairs_;
  bool hulls_found_ = false;
  std::vector<double> hull_slack_;  // SweptHull::slack of each of hulls_
  std::vector<std::pair<const GeomImpl*, const GeomImpl*>> hull_touching_;  // this step's shell pairs
  std::vector<dBodyID> robots_in_contact_;  // this step's chassis touching another robot
  std::vector<double> approach_;            // SweepRobots' per-contact approach speeds
  // With an ODE space: the planes, and the geometries that touch planes only (wheel ground
  // contacts, supports: nearly half a robot's). Those stay out of the space, where they would
  // be sorted and paired with everything near them each step only to be refused, and meet the
  // planes directly.
  std::vector<GeomImpl*> planes_;
  std::vector<GeomImpl*> planes_only_;
  // With an ODE space: each robot's other geometries in a simple space of their own inside it.
  // The broadphase then sorts one box per robot instead of each part's (pairs of one robot's
  // parts are all refused anyway), and a robot's box above the carpet skips its parts' plane
  // tests at once. Declared after space_: destroyed first, leaving it.
  std::unordered_map<const NodeImpl*, OdeSpace> robot_spaces_;
  // Resolved surfaces of the pairs that touched lately: a long run brings ever new pairs of
  // robot parts together, up to tens of thousands, so stale ones are swept out (and a hard
  // bound in collision.cpp).
  std::unordered_map<std::pair<const GeomImpl*, const GeomImpl*>, CachedSurface, PairHash> surfaces_;
  std::uint64_t passes_ = 0;  // Collide() calls so far
  SurfaceMaterial contact_surface_;  // reused per contact: no allocation once warm
};

}  // namespace ubersim::kernel
