// The run folder's place on disk, before anything is written or opened: its name (the default
// one under runs/, a given one checked for length), whether it can be created and written, and
// whether its file system has room for the profile's recordings. A bad folder is the operator's
// configuration (ConfigError, exit 2), said before any device opens.
#pragma once
#include <cstdint>
#include <filesystem>
#include <string>

#include "procedures/acceptance/profile.hpp"

namespace rig::cli {

// runs/<name>-<UTC time to the second>, claimed by creating it (a second run in the same second
// gets -2, -3, ...). `name`: folder_name_part of the serial or the profile's name.
std::string default_run_folder(const std::string& name);
// A serial or profile name made safe as one component of that name ('/', a leading '.', shell
// characters become '_'; at most 128 bytes).
std::string folder_name_part(std::string s);

// Refuses a folder name longer than a file system takes, or a path that with the run's own files
// in it would reach PATH_MAX. `option`: the option that named it (--out, --resume).
void refuse_a_name_too_long(const std::string& dir, const std::string& option);
// Creates `dir` and checks that a file can be written in it.
void prepare_run_folder(const std::string& dir, const std::string& option);
// A run.log already in `dir` (a stopped run's, a stopped start's) that this process cannot open
// to append to (the file made immutable, its permission taken away): a ConfigError naming it and
// the system's reason, before anything starts; the dry run's check too (touches nothing).
void refuse_a_run_log_it_cannot_write(const std::string& dir);
// Whether `d` holds a rig run: a regular run.json that rig wrote (its `software` "rig ..."; another
// tool's run.json, in a project folder that holds run folders, is not one).
bool holds_a_rig_run(const std::filesystem::path& d);
// A new run's folder must be one the run owns whole: not inside another run's folder (an
// ancestor holding rig's run.json: the new run's files would be that run's "added after the seal" for
// rig verify), and, for a sealed run, holding nothing the run does not write (verify names every
// other entry; a sealed PASS that could never verify, a technician's review). `taken_over`: a
// stopped start's files are there, the run's own. ConfigError before anything is written.
void refuse_a_folder_a_new_run_cannot_own(const std::string& dir, const std::string& option, bool sealed,
                                          bool taken_over);
// Whether this process can create a file in the existing directory `d` (touches nothing).
bool can_create_file_in(const std::filesystem::path& d);
// `p` itself, or its nearest ancestor that exists: where a folder not there yet would be created.
std::filesystem::path nearest_existing(std::filesystem::path p);

// Seconds of samples the profile records, and the bytes they take with the analysis beside them.
double recorded_seconds(const acceptance::Profile& p);
std::uint64_t recordings_bytes(const acceptance::Profile& p);
// The room on the file system of `dir` against the profile's recordings: a new run that cannot
// fit is refused (ConfigError), a resume warned on stderr. Returns the dry run's "Disk: ..." line.
std::string check_room(const std::string& dir, const std::string& option, const acceptance::Profile& p, bool resume);

}  // namespace rig::cli
