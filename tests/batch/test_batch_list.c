/*
 * tests/batch/test_batch_list.c -- a batch's garments without running them
 * (batch/batch.h): a folder is searched through its sub-folders, hidden
 * entries and earlier panelize outputs skipped; names are unique and sorted,
 * the same whatever order the inputs come in; every shard count splits the
 * garments exactly (each in one shard, shard I = orders I, I+N, ...; sizes
 * within one); manifests resolve their relative paths, take --name, quotes
 * and comments; bad shards, collisions and missing inputs are refused.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#define _POSIX_C_SOURCE 200809L
#include "batch/batch.h"

#include "test_files.h"

#include <stdlib.h>
#include <string.h>

#define GARMENTS 37

static void touch(const char *relative)
{
    char path[1024];
    test_temp_path(path, sizeof path, relative);
    for (char *slash = strchr(path + strlen(test_temp_dir) + 1, '/'); slash; slash = strchr(slash + 1, '/')) {
        *slash = '\0';
        mkdir(path, 0777);
        *slash = '/';
    }
    test_write_file(path, "", 0);
}

static void test_folder_and_shards(void)
{
    char relative[256];
    for (int i = 0; i < GARMENTS; ++i) {
        snprintf(relative, sizeof relative, "data/part%d/garment%02d.%s", i % 4, i, i % 3 ? "obj" : "PLY");
        touch(relative);
    }
    touch("data/.hidden.obj");
    touch("data/notes.txt");
    touch("data/old_output/garment.obj"); /* an earlier panelize output: not an input */
    touch("data/old_output/.panelize");
    char folder[512];
    test_temp_path(folder, sizeof folder, "data");
    pz_ctx ctx = {0};
    pz_batch_list *list = NULL;
    const char *inputs[] = {folder};
    REQUIRE_OK(pz_batch_list_read(inputs, 1, &list, &ctx), ctx);
    CHECK(list->count == GARMENTS, "%d garments found, %d made", (int)list->count, GARMENTS);
    for (int32_t i = 0; i < list->count; ++i) {
        CHECK(list->garments[i].order == i, "garment %d has order %d", (int)i, (int)list->garments[i].order);
        CHECK(i == 0 || strcmp(list->garments[i - 1].name, list->garments[i].name) < 0, "names not strictly sorted: %s, %s",
              list->garments[i - 1].name, list->garments[i].name);
        CHECK(strncmp(list->garments[i].name, "part", 4) == 0 && strchr(list->garments[i].name, '-'),
              "name %s is not partK-garmentNN", list->garments[i].name);
    }
    CHECK(strcmp(list->garments[0].name, "part0-garment00") == 0, "first name %s", list->garments[0].name);

    /* Every shard count partitions the list exactly. */
    for (int32_t shards = 1; shards <= 9; ++shards) {
        int seen[GARMENTS] = {0};
        int32_t smallest = GARMENTS, largest = 0;
        for (int32_t shard = 0; shard < shards; ++shard) {
            char text[32];
            int32_t index = -1, count = -1;
            snprintf(text, sizeof text, "%d/%d", (int)shard, (int)shards);
            REQUIRE_OK(pz_batch_shard_parse(text, &index, &count, &ctx), ctx);
            CHECK(index == shard && count == shards, "%s parsed as %d/%d", text, (int)index, (int)count);
            int32_t size = 0;
            for (int32_t i = 0; i < list->count; ++i)
                if (list->garments[i].order % count == index)
                    ++seen[i], ++size;
            smallest = size < smallest ? size : smallest;
            largest = size > largest ? size : largest;
        }
        for (int32_t i = 0; i < list->count; ++i)
            CHECK(seen[i] == 1, "%d shards: garment %d in %d shards", (int)shards, (int)i, seen[i]);
        CHECK(largest - smallest <= 1, "%d shards: sizes %d .. %d", (int)shards, (int)smallest, (int)largest);
    }

    /* The same garments named one by one (named by their base names then), forwards and in reverse: one order. */
    const char *files[GARMENTS], *backwards[GARMENTS];
    for (int32_t i = 0; i < list->count; ++i)
        files[i] = list->garments[i].path, backwards[i] = list->garments[list->count - 1 - i].path;
    pz_batch_list *forward = NULL, *reversed = NULL;
    REQUIRE_OK(pz_batch_list_read(files, (int)list->count, &forward, &ctx), ctx);
    REQUIRE_OK(pz_batch_list_read(backwards, (int)list->count, &reversed, &ctx), ctx);
    for (int32_t i = 0; i < list->count; ++i)
        CHECK(strcmp(reversed->garments[i].path, forward->garments[i].path) == 0, "order %d: %s vs %s", (int)i,
              reversed->garments[i].path, forward->garments[i].path);
    CHECK(strcmp(forward->garments[1].name, "garment01") == 0, "a file's name: %s", forward->garments[1].name);
    pz_batch_list_free(&forward);
    pz_batch_list_free(&reversed);

    /* Two folders each holding x.obj: two garments for one folder name. */
    touch("one/x.obj");
    touch("two/x.obj");
    char one[512], two[512];
    const char *twice[] = {test_temp_path(one, sizeof one, "one"), test_temp_path(two, sizeof two, "two")};
    pz_batch_list *clash = NULL;
    CHECK(pz_batch_list_read(twice, 2, &clash, &ctx) == PZ_ERR_USAGE && clash == NULL, "a collision: %s", ctx.error);
    CHECK(strstr(ctx.error, "would both write the folder x ") != NULL, "message: %s", ctx.error);
    pz_batch_list_free(&list);
    pz_batch_list_free(&list); /* twice: NULL is fine */
}

static void test_manifest(void)
{
    touch("m/meshes/a b+c.obj");
    touch("m/meshes/shirt.glb");
    char path[512];
    const char *text = "# garments\n"
                       "\n"
                       "meshes/shirt.glb --max-strain 0.1 --pose meshes/p1.obj --pose=meshes/p2.obj # poses\n"
                       "\"meshes/a b+c.obj\" --name Front\\Panel --iterations 5\n"
                       "/abs/dress.OBJ\n";
    test_write_file(test_temp_path(path, sizeof path, "m/list.txt"), text, strlen(text));
    pz_ctx ctx = {0};
    pz_batch_list *list = NULL;
    const char *inputs[] = {path};
    REQUIRE_OK(pz_batch_list_read(inputs, 1, &list, &ctx), ctx);
    REQUIRE(list->count == 3, "%d garments", (int)list->count);
    /* sorted by name: Front_Panel, dress, meshes-shirt */
    const pz_batch_garment *front = &list->garments[0], *dress = &list->garments[1], *shirt = &list->garments[2];
    CHECK(strcmp(front->name, "Front_Panel") == 0, "--name: %s", front->name);
    CHECK(strcmp(dress->name, "dress") == 0 && strcmp(dress->path, "/abs/dress.OBJ") == 0, "absolute: %s %s",
          dress->name, dress->path);
    CHECK(strcmp(shirt->name, "meshes-shirt") == 0, "relative: %s", shirt->name);
    char expected[1024];
    snprintf(expected, sizeof expected, "%s/m/meshes/a b+c.obj", test_temp_dir);
    CHECK(strcmp(front->path, expected) == 0, "quoted path resolved: %s", front->path);
    CHECK(front->arg_count == 2 && strcmp(front->args[0], "--iterations") == 0, "front's options: %d",
          front->arg_count);
    REQUIRE(shirt->arg_count == 5, "shirt's options: %d", shirt->arg_count);
    snprintf(expected, sizeof expected, "%s/m/meshes/p1.obj", test_temp_dir);
    CHECK(strcmp(shirt->args[3], expected) == 0, "--pose value resolved: %s", shirt->args[3]);
    snprintf(expected, sizeof expected, "--pose=%s/m/meshes/p2.obj", test_temp_dir);
    CHECK(strcmp(shirt->args[4], expected) == 0, "--pose=value resolved: %s", shirt->args[4]);
    CHECK(strcmp(shirt->args[1], "0.1") == 0, "other values untouched: %s", shirt->args[1]);
    CHECK(strstr(shirt->source, "list.txt:3") != NULL, "source: %s", shirt->source);
    pz_batch_list_free(&list);

    static const struct {
        const char *text, *where;
    } bad[] = {{"meshes/shirt.glb\n\"open.obj\n", "list.txt:2"},
               {"--iterations 5 shirt.obj\n", "list.txt:1"},
               {"notes.doc\n", "list.txt:1"},
               {"shirt.obj --name\n", "list.txt:1"},
               {"# nothing\n", "no garment"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        test_write_file(path, bad[i].text, strlen(bad[i].text));
        CHECK(pz_batch_list_read(inputs, 1, &list, &ctx) == PZ_ERR_USAGE && !list, "'%s' accepted", bad[i].text);
        CHECK(strstr(ctx.error, bad[i].where) != NULL, "'%s': message %s", bad[i].text, ctx.error);
    }
    const char *missing[] = {"/no/such/folder"};
    CHECK(pz_batch_list_read(missing, 1, &list, &ctx) == PZ_ERR_OPEN && !list, "missing: %s", ctx.error);
}

static void test_shard_text(void)
{
    static const char *const bad[] = {"3/3", "-1/3", "1/0", "a/b", "1/2x", "1", "", "0/100001", "1/-2"};
    pz_ctx ctx = {0};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int32_t index = 0, count = 0;
        CHECK(pz_batch_shard_parse(bad[i], &index, &count, &ctx) == PZ_ERR_USAGE, "'%s' accepted", bad[i]);
        CHECK(strstr(ctx.error, "--shard") != NULL, "message: %s", ctx.error);
    }
}

int main(void)
{
    test_temp_dir_create("pz_batch_list");
    test_folder_and_shards();
    test_manifest();
    test_shard_text();
    test_temp_dir_remove();
    return test_finish();
}
