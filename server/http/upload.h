// Reading what a client uploads, from the request cpp-httplib has parsed: the
// `file` and `options` parts of POST /v1/renders and /v1/conversions (or a raw
// body with query parameters, or a JSON body naming a stored file), and the
// `file`, `file_id` and `job` parts of POST /v1/jobs.
// Every duplicate, missing or unknown part is refused here, before any work
// (server/*.cpp and the fuzz harnesses only: this header pulls in httplib.h).
#pragma once

#include <httplib.h>

#include <initializer_list>
#include <string>
#include <vector>

#include "server/store/job_store.h"

namespace nurbsrt::server {

struct Upload {
    // The file's content (points into the request); nullptr when the request
    // names a stored file instead (file_id), whose bytes the route loads.
    const std::string* bytes = nullptr;
    std::string file_id;       // a stored file (server/store/file_store.h), as sent; "" for an upload
    std::string options_json;  // JSON object text: query parameters overlaid by the options part
    std::string filename;      // the `file` part's file name as sent ("" for a raw body)
    bool multipart = false;    // the file came as the `file` part of multipart/form-data
};
// A stored file is named by a `file_id` part instead of `file`, or by a JSON
// body {"file_id": "...", <options>} (Content-Type application/json), whose
// other members are the options (over the query parameters).
// Throws Error(invalid_argument) for a multipart body with neither or both of
// `file` and `file_id`, a JSON body without `file_id`, or a bad options part; Error(unsupported_format) for a raw body whose Content-Type is
// not a CAD or octet-stream type. Query parameter values are passed as strings,
// and so are the plain form fields named in `form_options` (`-F format=iges`);
// such a field given more than once, or also as a query parameter or in the
// options part, is refused.
Upload read_upload(const httplib::Request& req, std::initializer_list<const char*> form_options = {});

// The 400 detail for an upload without content: an empty raw body, or an
// empty `file` part; both say what to send instead.
std::string empty_upload_detail(const Upload& upload);
// The 400 detail for a POST without any body (neither Content-Length nor
// Transfer-Encoding) to `route` (server/routes/route_table.h): what that route expects.
std::string no_body_detail(const std::string& route);

// A download name for a result made from `upload_filename`: its stem (path,
// quotes and anything but letters, digits, '.', '-', '_' removed; "converted"
// when nothing is left) with `extension` (".igs", ...).
std::string download_name(const std::string& upload_filename, const std::string& extension);

struct JobUpload {
    // The `file` parts in order (index, filename, format, size), then the
    // `file_id` parts in order (index only: the route fills in the stored file's).
    std::vector<JobInput> inputs;
    std::vector<const std::string*> bytes;  // their contents (point into the request); nullptr for a file_id
    std::vector<std::string> file_ids;      // the stored file of each input; "" for an uploaded one
    const std::string* job_json = nullptr;  // the `job` part
};
// Throws Error(unsupported_format) for a body that is not multipart or a file
// that is neither STEP nor IGES, Error(limit_exceeded) beyond `max_job_files`
// files (uploaded and stored together), Error(invalid_argument) for an empty
// file, a missing or repeated `job` part, no file, or an unknown part.
JobUpload read_job_upload(const httplib::Request& req, int max_job_files);

}  // namespace nurbsrt::server
