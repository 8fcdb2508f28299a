-- Frames an episode uses, found by frame: removing a discarded import's unused frames asks,
-- for each frame, whether an episode uses it (as a frame or a thumbnail), and deleting a frame
-- checks the same references; without these each question read the whole table.
CREATE INDEX episode_frames_by_frame ON episode_frames (frame);
CREATE INDEX episode_frames_by_thumbnail ON episode_frames (thumbnail);
