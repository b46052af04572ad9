// Pieces the `pba` atlas, project and snapshot commands share: names of
// enum values, the list pager, one revision's download.
#pragma once

#include <filesystem>
#include <string>

#include "commands/atlas_commands.h"
#include "connection.h"
#include "exit_codes.h"

namespace pba::cli {

// A fresh random request id (32 hex characters) for a create, so that the
// server can tell a retried request from a new one; `given` when not empty
// (--request-id, for scripts that rerun a command safely).
std::string RequestIdOr(const std::string& given);

// "viewer", "editor", "admin"; "-" when unset.
// Uploads `file` (BeginUpload, then WriteUpload from where the server says
// it is, retried up to three times); *upload_id names the complete upload.
int UploadFile(Connection& connection, const std::string& file, std::string* upload_id);
// Tells the server to drop an upload this command abandons (DiscardUpload),
// so that it stops counting against the user's upload quota; best effort:
// a failure is ignored (the upload expires after a day anyway).
void DiscardUpload(Connection& connection, const std::string& upload_id);

std::string RoleText(v1::Role role);
// "contours_json", "nifti", "stl", "obj", "vtk"; "-" when unset.
std::string FormatText(v1::GeometryFormat format);
// The file extension a format's files take (".nii.gz" for NIfTI).
std::string Extension(v1::GeometryFormat format);
// "R,G,B".
std::string ColourText(const v1::Colour& c);
// Prints how to ask for the next page, when there is one.
void MoreHint(const std::string& next, const std::string& command);

// Downloads a revision's geometry into `out` (transfer.h: resumed, checked
// against the revision's SHA-256, links not followed; an existing `out`
// replaced only with `overwrite`).
int DownloadRevision(Connection& connection, const v1::Revision& revision,
                     const std::filesystem::path& out, bool overwrite);

// Revision `number` of `target` (0: the head); the exit code.
int GetHead(Connection& connection, const StructureArgs& target, int64_t number,
            v1::Revision* revision);

// Fetches one page of a list RPC, or with --all every page, into *all.
template <typename Request, typename Response, typename Item>
int FetchPages(Connection& connection, const PageArgs& page, Request request,
               grpc::Status (v1::AtlasService::Stub::*rpc)(grpc::ClientContext*, const Request&,
                                                           Response*),
               google::protobuf::RepeatedPtrField<Item>* (Response::*items)(),
               const std::string& what, Response* all) {
  request.set_page_size(page.page_size);
  std::string token = page.page_token;
  do {
    request.set_page_token(token);
    Response response;
    auto context = connection.UnaryContext();
    grpc::Status status = (connection.atlas().*rpc)(context.get(), request, &response);
    if (!status.ok()) return connection.Fail(what, status);
    for (Item& item : *(response.*items)()) *(all->*items)()->Add() = std::move(item);
    token = response.next_page_token();
  } while (page.all && !token.empty());
  all->set_next_page_token(token);
  return kExitOk;
}

}  // namespace pba::cli
