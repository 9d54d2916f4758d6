/*
 * studio/server.c -- the HTTP side of `panelize studio` (libmicrohttpd, a
 * thread per connection): the web app's files, and the API of
 * docs/studio.md routed to garments.c.
 *
 * What a request must be before it reaches any work: a Host naming this
 * machine when the server listens on loopback only (a page of another site
 * cannot reach it through a DNS name pointed at 127.0.0.1); a POST body of
 * JSON (Content-Type application/json) or, for an upload, of
 * application/octet-stream (so a plain HTML form of another site cannot post
 * to it); a body within max_upload bytes (413 otherwise, refused on its
 * Content-Length before it is read when that is given). Every refusal is a
 * 4xx answer {"error": "message"}.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _GNU_SOURCE
#include "studio/internal.h"
#include "core/util.h"
#include "io/io.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <microhttpd.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Names newer libmicrohttpd releases gave these codes. */
#ifndef MHD_HTTP_CONTENT_TOO_LARGE
#define MHD_HTTP_CONTENT_TOO_LARGE 413
#endif
#define STUDIO_HTTP_UNPROCESSABLE 422
#ifndef MHD_HTTP_HEADER_CONTENT_DISPOSITION
#define MHD_HTTP_HEADER_CONTENT_DISPOSITION "Content-Disposition"
#endif

/* The body of one request, collected across the access handler's calls. */
typedef struct request {
    char *body;
    size_t length, capacity;
    int too_large;
} request;

/* The pattern files the page may download (pz_result_write's names). */
static const char *const file_names[] = {"pattern.svg", "pattern.pdf", "pattern-tiled.pdf", "pattern.dxf",
                                         "marker.svg", "garment.glb", "garment.obj", "report.json",
                                         "report.html", "layout.obj"};

/* ---------------------------------------------------------------- answers */

static enum MHD_Result answer(struct MHD_Connection *connection, unsigned code, const char *type, char *text,
                              size_t length)
{
    struct MHD_Response *response = MHD_create_response_from_buffer(length, text, MHD_RESPMEM_MUST_FREE);
    if (!response) {
        free(text);
        return MHD_NO;
    }
    MHD_add_response_header(response, MHD_HTTP_HEADER_CONTENT_TYPE, type);
    MHD_add_response_header(response, MHD_HTTP_HEADER_CACHE_CONTROL, "no-store");
    MHD_add_response_header(response, "X-Content-Type-Options", "nosniff");
    enum MHD_Result queued = MHD_queue_response(connection, code, response);
    MHD_destroy_response(response);
    return queued;
}

static enum MHD_Result answer_json(struct MHD_Connection *connection, unsigned code, char *text)
{
    if (!text) {
        static const char nomem[] = "{\"error\":\"out of memory\"}";
        return answer(connection, MHD_HTTP_SERVICE_UNAVAILABLE, "application/json", strdup(nomem),
                      sizeof nomem - 1);
    }
    return answer(connection, code, "application/json", text, strlen(text));
}

/* {"key": "value"}, the string escaped. */
static enum MHD_Result answer_member(struct MHD_Connection *connection, unsigned code, const char *key,
                                     const char *value)
{
    cJSON *root = cJSON_CreateObject();
    if (root)
        cJSON_AddStringToObject(root, key, value);
    char *text = root ? cJSON_PrintUnformatted(root) : NULL;
    cJSON_Delete(root);
    return answer_json(connection, code, text);
}

static enum MHD_Result answer_error(struct MHD_Connection *connection, unsigned code, const char *message)
{
    return answer_member(connection, code, "error", message);
}

/* The HTTP code of a failed call: the request's fault (4xx) or ours (5xx). */
static unsigned status_code(pz_status status)
{
    switch (status) {
    case PZ_ERR_USAGE: return MHD_HTTP_BAD_REQUEST;
    case PZ_ERR_OPEN: return MHD_HTTP_NOT_FOUND;
    case PZ_ERR_DATA:
    case PZ_ERR_INVALID_MESH: return STUDIO_HTTP_UNPROCESSABLE;
    case PZ_ERR_CREATE: return MHD_HTTP_CONFLICT;
    case PZ_ERR_NOMEM: return MHD_HTTP_SERVICE_UNAVAILABLE;
    default: return MHD_HTTP_INTERNAL_SERVER_ERROR;
    }
}

static enum MHD_Result answer_status(struct MHD_Connection *connection, pz_status status, const pz_ctx *ctx)
{
    return answer_error(connection, status_code(status), ctx->error);
}

/* A file from disk with its type; 404 when it cannot be opened. */
static enum MHD_Result answer_file(struct MHD_Connection *connection, const char *path, const char *type,
                                   const char *download_name)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat info;
    if (fd < 0 || fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
        if (fd >= 0)
            close(fd);
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such file");
    }
    struct MHD_Response *response = MHD_create_response_from_fd((uint64_t)info.st_size, fd);
    if (!response) {
        close(fd);
        return MHD_NO;
    }
    MHD_add_response_header(response, MHD_HTTP_HEADER_CONTENT_TYPE, type);
    MHD_add_response_header(response, "X-Content-Type-Options", "nosniff");
    if (download_name) {
        char disposition[160];
        snprintf(disposition, sizeof disposition, "attachment; filename=\"%s\"", download_name);
        MHD_add_response_header(response, MHD_HTTP_HEADER_CONTENT_DISPOSITION, disposition);
    }
    enum MHD_Result queued = MHD_queue_response(connection, MHD_HTTP_OK, response);
    MHD_destroy_response(response);
    return queued;
}

static const char *content_type(const char *name)
{
    static const char *const types[][2] = {
        {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
        {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
        {".json", "application/json"}, {".svg", "image/svg+xml"}, {".png", "image/png"},
        {".pdf", "application/pdf"}, {".dxf", "application/dxf"}, {".glb", "model/gltf-binary"},
        {".obj", "text/plain; charset=utf-8"}};
    const char *dot = strrchr(name, '.');
    for (size_t i = 0; dot && i < sizeof types / sizeof types[0]; ++i)
        if (strcmp(dot, types[i][0]) == 0)
            return types[i][1];
    return "application/octet-stream";
}

/* ---------------------------------------------------------------- the web app */

/* GET / and /assets/NAME: files of the assets folder; names of [A-Za-z0-9._/-] without "..". */
static enum MHD_Result serve_asset(pz_studio *studio, struct MHD_Connection *connection, const char *url)
{
    const char *name = strcmp(url, "/") == 0 ? "index.html" : url + strlen("/assets/");
    if (!studio->assets[0])
        return answer_error(connection, MHD_HTTP_SERVICE_UNAVAILABLE,
                            "the studio's web app was not built (npm was missing at build time): the API works");
    if (!name[0] || strstr(name, "..") || strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                       "0123456789._/-") != strlen(name))
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such file");
    char path[PATH_MAX];
    if (snprintf(path, sizeof path, "%s/%s", studio->assets, name) >= (int)sizeof path)
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such file");
    return answer_file(connection, path, content_type(name), NULL);
}

/* ---------------------------------------------------------------- the API */

/* POST /api/garments {"path": "..."}: a garment under the allowed folder. */
static enum MHD_Result load_path(pz_studio *studio, struct MHD_Connection *connection, const request *body)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    char *path = NULL;
    char resolved[PATH_MAX];
    int id = 0;
    pz_status status = studio_json_string(body->body, body->length, "path", &path, &ctx);
    if (status == PZ_OK)
        status = studio_resolve_path(studio, path, 1, resolved, &ctx);
    if (status == PZ_OK && pz_format_from_path(resolved) == PZ_FORMAT_UNKNOWN)
        status = pz_error(&ctx, PZ_ERR_USAGE, "%s: not a mesh file (.obj, .ply, .off, .glb, .gltf)", path);
    if (status == PZ_OK)
        status = studio_garment_load(studio, resolved, path, &id, &ctx);
    free(path);
    if (status != PZ_OK)
        return answer_status(connection, status, &ctx);
    return answer_json(connection, MHD_HTTP_CREATED, studio_garment_json(studio, id));
}

/* POST /api/garments/upload?name=FILE.obj: the body is the file. */
static enum MHD_Result load_upload(pz_studio *studio, struct MHD_Connection *connection, const request *body)
{
    const char *name = MHD_lookup_connection_value(connection, MHD_GET_ARGUMENT_KIND, "name");
    if (!name || !name[0] || strlen(name) > 100 || name[0] == '.' ||
        strspn(name, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") != strlen(name))
        return answer_error(connection, MHD_HTTP_BAD_REQUEST,
                            "upload: ?name=FILE expected (letters, digits, '.', '_', '-'; up to 100)");
    if (pz_format_from_path(name) == PZ_FORMAT_UNKNOWN)
        return answer_error(connection, MHD_HTTP_BAD_REQUEST,
                            "upload: not a mesh file name (.obj, .ply, .off, .glb, .gltf)");
    if (body->length == 0)
        return answer_error(connection, MHD_HTTP_BAD_REQUEST, "upload: empty file");
    char path[PATH_MAX + 32];
    snprintf(path, sizeof path, "%s/upload-XXXXXX", studio->temp);
    int fd = mkstemp(path);
    int written = fd >= 0 && write(fd, body->body, body->length) == (ssize_t)body->length;
    if (fd >= 0)
        close(fd);
    char named[PATH_MAX + 160];
    snprintf(named, sizeof named, "%s-%s", path, name); /* the extension tells the reader the format */
    if (!written || rename(path, named) != 0) {
        unlink(path);
        return answer_error(connection, MHD_HTTP_INTERNAL_SERVER_ERROR, "upload: cannot store the file");
    }
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    int id = 0;
    pz_status status = studio_garment_load(studio, named, name, &id, &ctx);
    unlink(named);
    if (status != PZ_OK)
        return answer_status(connection, status, &ctx);
    return answer_json(connection, MHD_HTTP_CREATED, studio_garment_json(studio, id));
}

static enum MHD_Result start_run(pz_studio *studio, struct MHD_Connection *connection, int id, const request *body)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_run_options options;
    pz_sketch *sketch = NULL, *grain = NULL;
    /* The garment's mesh stays until its runs are done; the request reads its box under the lock. */
    pthread_mutex_lock(&studio->lock);
    studio_garment *garment = studio_garment_find(studio, id);
    pz_status status = garment ? studio_parse_run(body->body, body->length, garment->mesh, garment->welded, &options,
                                                  &sketch, &grain, &ctx)
                               : pz_error(&ctx, PZ_ERR_OPEN, "garment %d: not loaded", id);
    pthread_mutex_unlock(&studio->lock);
    int run_id = 0;
    if (status == PZ_OK)
        status = studio_run_start(studio, id, &options, sketch, grain, &run_id, &ctx);
    if (status != PZ_OK)
        return answer_status(connection, status, &ctx);
    char *text = NULL;
    if (asprintf(&text, "{\"run\":%d}", run_id) < 0)
        text = NULL;
    return answer_json(connection, MHD_HTTP_ACCEPTED, text);
}

/* GET .../files/NAME: the latest result's file (all written on the first such request). */
static enum MHD_Result serve_result_file(pz_studio *studio, struct MHD_Connection *connection, int id,
                                         const char *name)
{
    int known = 0;
    for (size_t i = 0; i < sizeof file_names / sizeof file_names[0]; ++i)
        known |= strcmp(name, file_names[i]) == 0;
    if (!known)
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such pattern file");
    studio_output *output = studio_output_get(studio, id);
    if (!output)
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no result yet");
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    pz_status status = studio_output_files(studio, output, &ctx);
    enum MHD_Result queued;
    if (status != PZ_OK)
        queued = answer_status(connection, status, &ctx);
    else {
        char path[PATH_MAX + 64];
        snprintf(path, sizeof path, "%s/%s", output->folder, name);
        queued = answer_file(connection, path, content_type(name), name);
    }
    studio_output_release(studio, output);
    return queued;
}

/* POST .../write {"folder": "..."}: the latest result's files into a folder under the allowed one. */
static enum MHD_Result write_result(pz_studio *studio, struct MHD_Connection *connection, int id,
                                    const request *body)
{
    pz_ctx ctx;
    pz_ctx_init(&ctx);
    ctx.quiet = 1;
    char *folder = NULL;
    char resolved[PATH_MAX];
    pz_status status = studio_json_string(body->body, body->length, "folder", &folder, &ctx);
    if (status == PZ_OK)
        status = studio_resolve_path(studio, folder, 0, resolved, &ctx);
    free(folder);
    studio_output *output = status == PZ_OK ? studio_output_get(studio, id) : NULL;
    if (status == PZ_OK && !output)
        status = pz_error(&ctx, PZ_ERR_OPEN, "garment %d: no result yet", id);
    if (status == PZ_OK)
        status = pz_output_folder_check(resolved, &ctx);
    if (status == PZ_OK) {
        pthread_mutex_lock(&output->write_lock);
        status = pz_result_write(output->result, resolved, PZ_OUTPUT_ALL, NULL, &ctx);
        pthread_mutex_unlock(&output->write_lock);
    }
    studio_output_release(studio, output);
    if (status != PZ_OK)
        return answer_status(connection, status, &ctx);
    return answer_member(connection, MHD_HTTP_OK, "folder", resolved);
}

/* /api/garments/ID/ACTION[/NAME]. */
static enum MHD_Result route_garment(pz_studio *studio, struct MHD_Connection *connection, const char *rest,
                                     int post, const request *body)
{
    char *end = NULL;
    errno = 0;
    long id = strtol(rest, &end, 10);
    if (end == rest || errno || id <= 0 || id > 1000000000 || (*end && *end != '/'))
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such garment");
    const char *action = *end ? end + 1 : "";
    int get = !post;
    if (get && !*action) {
        char *text = studio_garment_json(studio, (int)id);
        return text ? answer_json(connection, MHD_HTTP_OK, text)
                    : answer_error(connection, MHD_HTTP_NOT_FOUND, "no such garment");
    }
    if (get && strcmp(action, "status") == 0) {
        char *text = studio_status_json(studio, (int)id);
        return text ? answer_json(connection, MHD_HTTP_OK, text)
                    : answer_error(connection, MHD_HTTP_NOT_FOUND, "no such garment");
    }
    if (get && strcmp(action, "result") == 0) {
        studio_output *output = studio_output_get(studio, (int)id);
        if (!output)
            return answer_error(connection, MHD_HTTP_NOT_FOUND, "no result yet");
        char *copy = malloc(output->json_length);
        if (copy)
            memcpy(copy, output->json, output->json_length);
        size_t length = output->json_length;
        studio_output_release(studio, output);
        return copy ? answer(connection, MHD_HTTP_OK, "application/json", copy, length) : answer_json(connection, 0, NULL);
    }
    if (get && strcmp(action, "report") == 0) {
        studio_output *output = studio_output_get(studio, (int)id);
        if (!output)
            return answer_error(connection, MHD_HTTP_NOT_FOUND, "no result yet");
        pz_ctx ctx;
        pz_ctx_init(&ctx);
        ctx.quiet = 1;
        pthread_mutex_lock(&output->write_lock); /* what the run deferred, as report.json has it */
        pz_status status = pz_result_complete(output->result, &ctx);
        cJSON *report = status == PZ_OK ? pz_result_report(output->result) : NULL; /* report.json's content */
        pthread_mutex_unlock(&output->write_lock);
        char *text = report ? cJSON_PrintUnformatted(report) : NULL;
        cJSON_Delete(report);
        studio_output_release(studio, output);
        return answer_json(connection, MHD_HTTP_OK, text);
    }
    if (get && strncmp(action, "files/", 6) == 0)
        return serve_result_file(studio, connection, (int)id, action + 6);
    if (post && strcmp(action, "run") == 0)
        return start_run(studio, connection, (int)id, body);
    if (post && strcmp(action, "cancel") == 0)
        return studio_run_cancel(studio, (int)id) ? answer_json(connection, MHD_HTTP_OK, strdup("{}"))
                                                  : answer_error(connection, MHD_HTTP_NOT_FOUND, "no such garment");
    if (post && strcmp(action, "write") == 0)
        return write_result(studio, connection, (int)id, body);
    return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such request (docs/studio.md lists them)");
}

/* ---------------------------------------------------------------- checks and the handler */

/* Host must name this machine (with any port) when listening on loopback only. */
static int host_allowed(const pz_studio *studio, struct MHD_Connection *connection)
{
    if (!studio->local_only)
        return 1;
    const char *host = MHD_lookup_connection_value(connection, MHD_HEADER_KIND, MHD_HTTP_HEADER_HOST);
    if (!host)
        return 0;
    static const char *const names[] = {"127.0.0.1", "localhost", "[::1]"};
    for (int i = 0; i < 3; ++i) {
        size_t length = strlen(names[i]);
        if (strncmp(host, names[i], length) == 0 && (host[length] == '\0' || host[length] == ':'))
            return 1;
    }
    return 0;
}

static int content_type_is(struct MHD_Connection *connection, const char *wanted)
{
    const char *type = MHD_lookup_connection_value(connection, MHD_HEADER_KIND, MHD_HTTP_HEADER_CONTENT_TYPE);
    size_t length = strlen(wanted);
    return type && strncasecmp(type, wanted, length) == 0 && (type[length] == '\0' || type[length] == ';');
}

/* Appends upload data to the request's body, up to the limit (beyond it the rest is read and dropped). */
static void collect(request *body, const char *data, size_t size, size_t limit)
{
    if (body->too_large || body->length + size > limit) {
        body->too_large = 1;
        return;
    }
    if (!pz_grow((void **)&body->body, &body->capacity, body->length + size + 1, 1)) {
        body->too_large = 1;
        return;
    }
    memcpy(body->body + body->length, data, size);
    body->length += size;
    body->body[body->length] = '\0';
}

static enum MHD_Result handle(void *cls, struct MHD_Connection *connection, const char *url, const char *method,
                              const char *version, const char *upload_data, size_t *upload_data_size,
                              void **con_cls)
{
    (void)version;
    pz_studio *studio = cls;
    int post = strcmp(method, "POST") == 0;
    if (!*con_cls) { /* the first call: headers only */
        request *body = calloc(1, sizeof *body);
        if (!body)
            return MHD_NO;
        *con_cls = body;
        const char *length = MHD_lookup_connection_value(connection, MHD_HEADER_KIND,
                                                         MHD_HTTP_HEADER_CONTENT_LENGTH);
        if (length && strtoull(length, NULL, 10) > studio->max_upload)
            return answer_error(connection, MHD_HTTP_CONTENT_TOO_LARGE, "the request is too large");
        return MHD_YES;
    }
    request *body = *con_cls;
    if (*upload_data_size) {
        collect(body, upload_data, *upload_data_size, studio->max_upload);
        *upload_data_size = 0;
        return MHD_YES;
    }
    if (!host_allowed(studio, connection))
        return answer_error(connection, MHD_HTTP_FORBIDDEN, "Host must be 127.0.0.1 or localhost");
    if (body->too_large)
        return answer_error(connection, MHD_HTTP_CONTENT_TOO_LARGE, "the request is too large");
    if (!post && strcmp(method, "GET") != 0 && strcmp(method, "HEAD") != 0)
        return answer_error(connection, MHD_HTTP_METHOD_NOT_ALLOWED, "only GET and POST");
    if (!post && (strcmp(url, "/") == 0 || strncmp(url, "/assets/", 8) == 0))
        return serve_asset(studio, connection, url);
    if (strncmp(url, "/api/", 5) != 0)
        return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such page");
    int upload = post && strcmp(url, "/api/garments/upload") == 0;
    if (post && !content_type_is(connection, upload ? "application/octet-stream" : "application/json"))
        return answer_error(connection, MHD_HTTP_UNSUPPORTED_MEDIA_TYPE,
                            upload ? "an upload is Content-Type application/octet-stream"
                                   : "a request is Content-Type application/json");
    if (upload)
        return load_upload(studio, connection, body);
    if (strcmp(url, "/api/garments") == 0)
        return post ? load_path(studio, connection, body)
                    : answer_json(connection, MHD_HTTP_OK, studio_garments_list_json(studio));
    if (strncmp(url, "/api/garments/", 14) == 0)
        return route_garment(studio, connection, url + 14, post, body);
    return answer_error(connection, MHD_HTTP_NOT_FOUND, "no such request (docs/studio.md lists them)");
}

static void completed(void *cls, struct MHD_Connection *connection, void **con_cls,
                      enum MHD_RequestTerminationCode code)
{
    (void)cls, (void)connection, (void)code;
    request *body = *con_cls;
    if (body)
        free(body->body);
    free(body);
    *con_cls = NULL;
}

/* ---------------------------------------------------------------- start and stop */

void pz_studio_options_default(pz_studio_options *options)
{
    memset(options, 0, sizeof *options);
    options->port = 8008;
    options->max_upload = PZ_STUDIO_DEFAULT_MAX_UPLOAD;
}

/* The web app's folder: options->assets, $PZ_STUDIO_ASSETS, or share/panelize/studio beside the
 * executable (build tree) or one level up (installed); "" when none has index.html. */
static void find_assets(const pz_studio_options *options, char *out)
{
    char candidates[4][PATH_MAX] = {{0}};
    if (options->assets)
        snprintf(candidates[0], PATH_MAX, "%s", options->assets);
    else {
        const char *environment = getenv("PZ_STUDIO_ASSETS");
        if (environment)
            snprintf(candidates[1], PATH_MAX, "%s", environment);
        char exe[PATH_MAX];
        ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
        if (length > 0) {
            exe[length] = '\0';
            char *slash = strrchr(exe, '/');
            if (slash)
                *slash = '\0';
            snprintf(candidates[2], PATH_MAX, "%.*s/share/panelize/studio", PATH_MAX - 32, exe);
            snprintf(candidates[3], PATH_MAX, "%.*s/../share/panelize/studio", PATH_MAX - 32, exe);
        }
    }
    out[0] = '\0';
    for (int i = 0; i < 4; ++i) {
        char index[PATH_MAX + 32];
        snprintf(index, sizeof index, "%.*s/index.html", PATH_MAX - 1, candidates[i]);
        if (candidates[i][0] && access(index, R_OK) == 0 && realpath(candidates[i], out))
            return;
    }
    out[0] = '\0';
}

static int remove_entry(const char *path, const struct stat *info, int flag, struct FTW *ftw)
{
    (void)info, (void)flag, (void)ftw;
    remove(path);
    return 0;
}

void pz_studio_stop(pz_studio **studio_pointer)
{
    if (!studio_pointer || !*studio_pointer)
        return;
    pz_studio *studio = *studio_pointer;
    if (studio->daemon)
        MHD_stop_daemon(studio->daemon);
    studio_garments_free(studio);
    if (studio->temp[0])
        nftw(studio->temp, remove_entry, 16, FTW_DEPTH | FTW_PHYS);
    pthread_mutex_destroy(&studio->lock);
    free(studio);
    *studio_pointer = NULL;
}

/* The listening address: IPv4 or IPv6 text into *address (sockaddr_in or sockaddr_in6). */
static pz_status parse_listen(const char *listen, int port, struct sockaddr_storage *address, int *ipv6,
                              pz_ctx *ctx)
{
    memset(address, 0, sizeof *address);
    struct sockaddr_in *v4 = (struct sockaddr_in *)address;
    struct sockaddr_in6 *v6 = (struct sockaddr_in6 *)address;
    *ipv6 = 0;
    if (inet_pton(AF_INET, listen, &v4->sin_addr) == 1) {
        v4->sin_family = AF_INET;
        v4->sin_port = htons((uint16_t)port);
        return PZ_OK;
    }
    if (inet_pton(AF_INET6, listen, &v6->sin6_addr) == 1) {
        v6->sin6_family = AF_INET6;
        v6->sin6_port = htons((uint16_t)port);
        *ipv6 = 1;
        return PZ_OK;
    }
    return pz_error(ctx, PZ_ERR_USAGE, "studio: --listen: '%s' is not an IPv4 or IPv6 address", listen);
}

pz_status pz_studio_start(const pz_studio_options *options, pz_studio **out, pz_ctx *ctx)
{
    *out = NULL;
    pz_studio_options defaults;
    if (!options) {
        pz_studio_options_default(&defaults);
        options = &defaults;
    }
    if (options->port < 0 || options->port > 65535)
        return pz_error(ctx, PZ_ERR_USAGE, "studio: --port: %d is not 0 .. 65535", options->port);
    const char *listen = options->listen ? options->listen : "127.0.0.1";
    struct sockaddr_storage address;
    int ipv6 = 0;
    pz_status status = parse_listen(listen, options->port, &address, &ipv6, ctx);
    if (status != PZ_OK)
        return status;
    pz_studio *studio = calloc(1, sizeof *studio);
    if (!studio)
        return pz_error(ctx, PZ_ERR_NOMEM, "studio: out of memory");
    pthread_mutex_init(&studio->lock, NULL);
    studio->max_upload = options->max_upload ? options->max_upload : PZ_STUDIO_DEFAULT_MAX_UPLOAD;
    studio->local_only = strcmp(listen, "127.0.0.1") == 0 || strcmp(listen, "::1") == 0;
    const char *root = options->root ? options->root : ".";
    struct stat info;
    if (!realpath(root, studio->root) || stat(studio->root, &info) != 0 || !S_ISDIR(info.st_mode)) {
        pz_studio_stop(&studio);
        return pz_error(ctx, PZ_ERR_OPEN, "studio: %s: not a readable folder", root);
    }
    find_assets(options, studio->assets);
    const char *tmp = getenv("TMPDIR");
    snprintf(studio->temp, sizeof studio->temp, "%s/panelize-studio-XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(studio->temp)) {
        studio->temp[0] = '\0';
        pz_studio_stop(&studio);
        return pz_error(ctx, PZ_ERR_CREATE, "studio: cannot make a temporary folder: %s", strerror(errno));
    }
    if (options->garment) {
        char resolved[PATH_MAX];
        int id = 0;
        status = studio_resolve_path(studio, options->garment, 1, resolved, ctx);
        if (status == PZ_OK)
            status = studio_garment_load(studio, resolved, options->garment, &id, ctx);
        if (status != PZ_OK) {
            pz_studio_stop(&studio);
            return status == PZ_ERR_USAGE ? PZ_ERR_OPEN : status;
        }
    }
    unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD | MHD_USE_THREAD_PER_CONNECTION | (ipv6 ? MHD_USE_IPv6 : 0);
    studio->daemon = MHD_start_daemon(flags, (uint16_t)options->port, NULL, NULL, handle, studio,
                                      MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&address,
                                      MHD_OPTION_NOTIFY_COMPLETED, completed, studio,
                                      MHD_OPTION_CONNECTION_LIMIT, (unsigned)64,
                                      MHD_OPTION_CONNECTION_TIMEOUT, (unsigned)120, MHD_OPTION_END);
    if (!studio->daemon) {
        pz_studio_stop(&studio);
        return pz_error(ctx, PZ_ERR_CREATE, "studio: cannot listen on %s port %d (in use?)", listen, options->port);
    }
    const union MHD_DaemonInfo *bound = MHD_get_daemon_info(studio->daemon, MHD_DAEMON_INFO_BIND_PORT);
    studio->port = bound ? bound->port : options->port;
    snprintf(studio->url, sizeof studio->url, ipv6 ? "http://[%s]:%d/" : "http://%s:%d/", listen, studio->port);
    *out = studio;
    return PZ_OK;
}

const char *pz_studio_url(const pz_studio *studio)
{
    return studio->url;
}
