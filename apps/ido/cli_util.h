// SPDX-License-Identifier: Apache-2.0
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "ido/core/atomic_file.h"
#include "ido/core/math.h"
#include "ido/core/progress.h"
#include "ido/geometry/aabb.h"
#include "ido/segment/organ.h"

namespace ido::cli {

/// Parses "X,Y,Z" into a vector. @p what names the argument in the error message.
/// @throws ido::InvalidInput on anything but three finite numbers.
Vec3 parse_vec3(std::string_view text, std::string_view what);

/// Parses "I,J,K" into integer indices; @throws ido::InvalidInput.
Index3 parse_index3(std::string_view text, std::string_view what);

/// Parses "x0,y0,z0,x1,y1,z1" (world mm) into a box's corners, naming --roi in errors.
/// @throws ido::InvalidInput on anything but six numbers with each minimum below its maximum.
geometry::Aabb parse_roi(const std::string& text);

/// The organ named by option @p option's value @p name (segment::parse_organ).
/// @throws ido::InvalidInput naming the option and the choices.
segment::Organ parse_organ_option(const std::string& name, std::string_view option);

/// The balloon options a command's flags ask for (segment::balloon_options), its errors naming
/// each flag with @p prefix ("--" for `ido segment`, "--vessel-" for `ido pipeline`); on the
/// command line reference and tolerance are given together or not at all.
/// @throws ido::InvalidInput.
segment::BalloonOptions balloon_options_from_flags(std::string_view prefix, const segment::BalloonChoices& choices);

/// A Progress that draws a bar on stderr when stderr is a terminal and quiet is off,
/// and reports nothing otherwise.
std::unique_ptr<Progress> make_progress(bool quiet);

/// Writes @p text to @p path atomically (temp file + rename).
void write_text_file(const std::string& path, const std::string& text);

/// Checks, before any work, that @p path can be written as an output file: not a folder, its
/// folder exists, and a file can be created there (probed with a temporary file that is
/// removed at once). @throws ido::InvalidInput naming @p option and the path.
void check_output_file(const std::string& path, std::string_view option);

/// The outputs of one run, written all or none: stage() checks a target (check_output_file)
/// and gives the path to write instead (the same file name in a hidden staging folder beside
/// it, ido::FileBatch); commit() renames every staged file into place. Until then nothing is at the targets, and a batch destroyed
/// uncommitted (an exception) removes its temporaries; a fatal signal removes them too
/// (ido::FileBatch, install_signal_cleanup), or waits for a commit under way to end.
class OutputBatch {
 public:
  /// @throws ido::InvalidInput as check_output_file.
  std::string stage(const std::string& path, std::string_view option);
  /// @throws ido::IoError naming the target that could not be put in place.
  void commit();

 private:
  FileBatch m_batch;
};

}  // namespace ido::cli
