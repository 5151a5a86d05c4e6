// encoder_channel: one encoder (A and B pins) from the pins to the captured window.
//
// input_conditioner x2 -> quadrature_decoder -> window_counter, plus the per-channel illegal
// transition counter (OMNILOC_ERROR_COUNT_BITS wide, saturating, never cleared except by reset:
// the host needs to know that a channel has a fault, not how many thousands).
// Latency from a pin change to the count: conditioner (3 cycles, or FILTER + 2 when FILTER > 1)
// + decoder (1 cycle); a pulse of the decoder is in the window whose capture_i is at or after it.
//
// Assumptions: a_i/b_i asynchronous; filter_len_i, mode_i and en_i from the register file
// (mode_i never 3); capture_i one-cycle pulses. rst_i synchronous, active high.
`resetall
`timescale 1ns / 1ps
`default_nettype none

`include "omniloc_regs.vh"

module encoder_channel (
    input  wire                                 clk_i,
    input  wire                                 rst_i,
    input  wire                                 a_i,
    input  wire                                 b_i,
    input  wire [`OMNILOC_FILTER_LENGTH_W-1:0]  filter_len_i,
    input  wire                                 en_i,
    input  wire [`OMNILOC_CONTROL_DECODE_W-1:0] mode_i,
    input  wire                                 capture_i,
    output wire [`OMNILOC_DATA_W-1:0]           win_count_o,
    output wire [`OMNILOC_DATA_W-1:0]           win_position_o,
    output wire                                 win_dir_o,
    output wire [`OMNILOC_DATA_W-1:0]           position_o,
    output wire                                 dir_o,
    // One-cycle pulse per illegal transition, and their saturating count.
    output wire                                 err_o,
    output wire [`OMNILOC_ERROR_COUNT_BITS-1:0] err_count_o
);

localparam integer DATA_W = `OMNILOC_DATA_W;
localparam integer ERR_W = `OMNILOC_ERROR_COUNT_BITS;

wire a_clean;
wire b_clean;
wire a_valid;
wire b_valid;
wire up;
wire down;

input_conditioner #(.LEN_W(`OMNILOC_FILTER_LENGTH_W)) u_cond_a (
    .clk_i(clk_i), .rst_i(rst_i), .in_i(a_i), .len_i(filter_len_i),
    .out_o(a_clean), .valid_o(a_valid)
);

input_conditioner #(.LEN_W(`OMNILOC_FILTER_LENGTH_W)) u_cond_b (
    .clk_i(clk_i), .rst_i(rst_i), .in_i(b_i), .len_i(filter_len_i),
    .out_o(b_clean), .valid_o(b_valid)
);

quadrature_decoder u_dec (
    .clk_i(clk_i), .rst_i(rst_i), .a_i(a_clean), .b_i(b_clean),
    .valid_i(a_valid & b_valid), .en_i(en_i), .mode_i(mode_i),
    .up_o(up), .down_o(down), .dir_o(dir_o), .err_o(err_o)
);

window_counter #(.W(DATA_W)) u_win (
    .clk_i(clk_i), .rst_i(rst_i), .up_i(up), .down_i(down), .dir_i(dir_o),
    .capture_i(capture_i), .win_count_o(win_count_o), .win_position_o(win_position_o),
    .win_dir_o(win_dir_o), .position_o(position_o)
);

reg [ERR_W-1:0] err_count_q;
assign err_count_o = err_count_q;

always @(posedge clk_i) begin
    if (rst_i) begin
        err_count_q <= {ERR_W{1'b0}};
    end else if (err_o && err_count_q != {ERR_W{1'b1}}) begin
        err_count_q <= err_count_q + 1'b1;
    end
end

endmodule

`resetall
